#pragma once
// How a following replica's polls of its primary are going, for GET /api/v1/registry: a replica
// whose follow loop broke (its token revoked, its primary gone) still serves its last snapshot and
// stays ready, so this is where an operator sees that it has fallen behind.

#include <chrono>
#include <mutex>
#include <optional>
#include <string>

namespace pintag::replica {

class FollowStatus {
 public:
  using Clock = std::chrono::system_clock;

  struct View {
    std::optional<Clock::time_point> last_answer;  ///< the primary's last 200 or 304
    std::string error;                             ///< the last poll's error, when it failed
    std::optional<Clock::time_point> failing_since;
  };

  void succeeded() {
    const std::lock_guard lock(mutex_);
    view_.last_answer = Clock::now();
    view_.error.clear();
    view_.failing_since.reset();
  }
  void failed(std::string error) {
    const std::lock_guard lock(mutex_);
    view_.error = std::move(error);
    if (!view_.failing_since) view_.failing_since = Clock::now();
  }
  View view() const {
    const std::lock_guard lock(mutex_);
    return view_;
  }

 private:
  mutable std::mutex mutex_;
  View view_;
};

}  // namespace pintag::replica
