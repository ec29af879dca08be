#include "progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace pintag::bench {
namespace {

std::string Duration(double seconds) {
  const int s = static_cast<int>(std::lround(seconds));
  char buf[32];
  std::snprintf(buf, sizeof buf, "%d:%02d", s / 60, s % 60);
  return buf;
}

}  // namespace

Progress::Progress(std::size_t total, bool quiet)
    : total_(std::max<std::size_t>(total, 1)),
      quiet_(quiet),
      tty_(isatty(STDERR_FILENO) == 1),
      start_(Clock::now()),
      last_print_(start_) {}

void Progress::update(std::size_t done, const std::string& what) {
  if (quiet_) return;
  const auto now = Clock::now();
  const double since_print = std::chrono::duration<double>(now - last_print_).count();
  if (since_print < (tty_ ? 0.2 : 10.0)) return;
  last_print_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double fraction = std::min(1.0, static_cast<double>(done) / static_cast<double>(total_));
  const std::string eta = fraction > 0.01 ? Duration(elapsed / fraction - elapsed) : "?";
  if (tty_) {
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(fraction * kWidth);
    std::string bar(static_cast<std::size_t>(filled), '#');
    bar.resize(kWidth, '.');
    std::fprintf(stderr, "\r[%s] %5.1f %%  %zu/%zu  elapsed %s  left ~%s  %-22s", bar.c_str(),
                 100 * fraction, done, total_, Duration(elapsed).c_str(), eta.c_str(),
                 what.c_str());
  } else {
    std::fprintf(stderr, "pintag_bench: %5.1f %% (%zu/%zu), elapsed %s, left ~%s, %s\n",
                 100 * fraction, done, total_, Duration(elapsed).c_str(), eta.c_str(),
                 what.c_str());
  }
  std::fflush(stderr);
}

void Progress::finish(const std::string& summary) {
  if (quiet_) return;
  const double elapsed = std::chrono::duration<double>(Clock::now() - start_).count();
  std::fprintf(stderr, "%spintag_bench: %s in %s\n", tty_ ? "\r\033[K" : "", summary.c_str(),
               Duration(elapsed).c_str());
}

}  // namespace pintag::bench
