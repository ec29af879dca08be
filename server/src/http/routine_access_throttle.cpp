#include "pintag/server/routine_access_throttle.hpp"

namespace pintag::server {

std::optional<std::size_t> RoutineAccessThrottle::admit(const std::string& kind,
                                                        Clock::time_point now) {
  const std::lock_guard lock(mutex_);
  if (const auto found = kinds_.find(kind); found != kinds_.end()) {
    Written& written = found->second;
    if (now - written.at < interval_) {
      ++written.left_out_since;
      return std::nullopt;
    }
    const std::size_t left_out = written.left_out_since;
    written = {.at = now, .left_out_since = 0};
    return left_out;
  }
  if (kinds_.size() >= max_kinds_) {
    // A kind whose interval is over would be written at its next line anyway; only the count of
    // lines it left out since is lost with it.
    std::erase_if(kinds_, [&](const auto& entry) { return now - entry.second.at >= interval_; });
    if (kinds_.size() >= max_kinds_) return 0;
  }
  kinds_.emplace(kind, Written{.at = now, .left_out_since = 0});
  return 0;
}

}  // namespace pintag::server
