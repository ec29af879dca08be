#include "app/write_gate.hpp"

#include <algorithm>
#include <string>
#include <utility>

#include "pintag/server/problem.hpp"

namespace pintag::app {

WriteGate::WriteGate(int capacity) : capacity_(std::max(1, capacity)) {}

WriteGate::Permit::~Permit() {
  if (gate_ == nullptr) return;
  {
    const std::lock_guard lock(gate_->mutex_);
    auto& entered = gate_->entered_;
    entered.erase(std::find(entered.begin(), entered.end(), entered_));
  }
  gate_->left_.notify_one();
}

WriteGate::Permit WriteGate::enter() {
  std::unique_lock lock(mutex_);
  while (std::cmp_greater_equal(entered_.size(), capacity_)) {
    const Clock::time_point stuck_at = *std::min_element(entered_.begin(), entered_.end()) + kStuck;
    if (Clock::now() >= stuck_at) {
      throw server::HttpError(server::Problem{
          503, "Writers Busy",
          std::to_string(capacity_) +
              " requests have been writing the database (or waiting for its lock) for a second "
              "or more; nothing was written, try again",
          "about:blank", /*retry_after_seconds=*/1});
    }
    left_.wait_until(lock, stuck_at);
  }
  const Clock::time_point now = Clock::now();
  entered_.push_back(now);
  return Permit(this, now);
}

int WriteGateCapacity(int threads) {
  return std::max(1, threads / 2);
}

}  // namespace pintag::app
