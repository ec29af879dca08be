#pragma once
// A warning that could be written once a request (a database that cannot be opened, under a
// fleet of scanners) is written the first time, then at most once an interval, with how many
// like it were left out (any message counts as like it), and once more when the trouble has
// passed. Each of those requests still has its own access line. Thread-safe.

#include <chrono>
#include <cstddef>
#include <mutex>
#include <optional>
#include <string>

namespace pintag::server {

class LogThrottle {
 public:
  using Clock = std::chrono::steady_clock;

  explicit LogThrottle(Clock::duration interval = std::chrono::seconds(10)) : interval_(interval) {}

  /// The line to write for this occurrence at `now`, or nothing when it is left out: the first
  /// occurrence, and the first one an interval after the last written, are written, the latter
  /// saying how many were left out since.
  std::optional<std::string> admit(std::string message, Clock::time_point now = Clock::now());

  /// The trouble has passed (the database opens again): the line to write when an occurrence was
  /// written since the last settle and none came in the last interval, saying how many were left
  /// out after the one written; nothing otherwise. The next occurrence is then written at once.
  std::optional<std::string> settle(std::string message, Clock::time_point now = Clock::now());

 private:
  const Clock::duration interval_;
  std::mutex mutex_;
  std::optional<Clock::time_point> last_written_;
  std::optional<Clock::time_point> last_occurred_;
  std::size_t left_out_ = 0;
};

}  // namespace pintag::server
