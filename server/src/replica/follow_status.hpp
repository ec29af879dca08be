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
  /// A poll that failed; `answered` when the primary did answer it (200 or 304), and what it
  /// sent was refused (a registry that gives a served key to another pincode, a snapshot cut
  /// short): the primary is up, so its last answer is now.
  void failed(std::string error, bool answered = false) {
    const std::lock_guard lock(mutex_);
    if (answered) view_.last_answer = Clock::now();
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
