#pragma once
// Access lines of routine requests, the ones a route marks as asked over and over with nothing
// to report (a replica's snapshot poll answered 304 Not Modified, once a second per replica:
// 86,400 lines a day each), are written at most once an interval for each kind: the same client,
// token, method, path and status. A line written after some were left out says how many. Any
// other answer of the route (a 200 with a new snapshot, a 401) is not routine and always
// written. Thread-safe.

#include <chrono>
#include <cstddef>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>

namespace pintag::server {

class RoutineAccessThrottle {
 public:
  using Clock = std::chrono::steady_clock;

  /// `max_kinds` bounds the memory: past it, kinds last written an interval ago are forgotten,
  /// and when none is, a new kind's lines are written, none left out.
  explicit RoutineAccessThrottle(Clock::duration interval = std::chrono::minutes(1),
                                 std::size_t max_kinds = 4096)
      : interval_(interval), max_kinds_(max_kinds) {}

  /// Nothing when the line of this kind at `now` is left out; else how many lines of its kind
  /// were left out since the last one written (0 for the first).
  std::optional<std::size_t> admit(const std::string& kind, Clock::time_point now = Clock::now());

 private:
  struct Written {
    Clock::time_point at;
    std::size_t left_out_since = 0;
  };

  const Clock::duration interval_;
  const std::size_t max_kinds_;
  std::mutex mutex_;
  std::unordered_map<std::string, Written> kinds_;
};

}  // namespace pintag::server
