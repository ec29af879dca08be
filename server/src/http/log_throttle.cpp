#include "pintag/server/log_throttle.hpp"

#include <utility>

namespace pintag::server {
namespace {

std::string WholeSeconds(LogThrottle::Clock::duration elapsed) {
  return std::to_string(std::chrono::duration_cast<std::chrono::seconds>(elapsed).count());
}

}  // namespace

std::optional<std::string> LogThrottle::admit(std::string message, Clock::time_point now) {
  const std::lock_guard lock(mutex_);
  last_occurred_ = now;
  if (last_written_ && now - *last_written_ < interval_) {
    ++left_out_;
    return std::nullopt;
  }
  if (left_out_ > 0) {
    message += " (and " + std::to_string(left_out_) + " more like it in the " +
               WholeSeconds(now - *last_written_) + " s before)";
  }
  last_written_ = now;
  left_out_ = 0;
  return message;
}

std::optional<std::string> LogThrottle::settle(std::string message, Clock::time_point now) {
  const std::lock_guard lock(mutex_);
  // Trouble that comes and goes (descriptors running out) is not over at its first success.
  if (!last_written_ || now - *last_occurred_ < interval_) return std::nullopt;
  if (left_out_ > 0) {
    message += " (" + std::to_string(left_out_) + " more like the last warning were left out in " +
               "the " + WholeSeconds(now - *last_written_) + " s after it)";
  }
  last_written_.reset();
  left_out_ = 0;
  return message;
}

}  // namespace pintag::server
