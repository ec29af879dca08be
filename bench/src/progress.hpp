#pragma once
// Progress of the sweep on stderr: a bar redrawn in place when stderr is a terminal, a plain line
// every 10 seconds (and at the end) otherwise, so CI logs stay readable.

#include <chrono>
#include <cstddef>
#include <string>

namespace pintag::bench {

class Progress {
 public:
  /// `total` units of work; `quiet` prints nothing.
  Progress(std::size_t total, bool quiet = false);
  /// `done` units finished so far; `what` says what is running now (e.g. "detect 1 thread").
  void update(std::size_t done, const std::string& what);
  /// Final line (newline after the bar).
  void finish(const std::string& summary);

 private:
  using Clock = std::chrono::steady_clock;
  std::size_t total_;
  bool quiet_;
  bool tty_;
  Clock::time_point start_;
  Clock::time_point last_print_;
};

}  // namespace pintag::bench
