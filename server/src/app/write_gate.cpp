#include "app/write_gate.hpp"

#include <algorithm>
#include <string>

#include "pintag/server/problem.hpp"

namespace pintag::app {

WriteGate::WriteGate(int capacity) : capacity_(std::max(1, capacity)) {}

WriteGate::Permit::~Permit() {
  if (gate_ == nullptr) return;
  const std::lock_guard lock(gate_->mutex_);
  --gate_->writers_;
}

WriteGate::Permit WriteGate::enter() {
  {
    const std::lock_guard lock(mutex_);
    if (writers_ < capacity_) {
      ++writers_;
      return Permit(this);
    }
  }
  throw server::HttpError(server::Problem{
      503, "Writers Busy",
      std::to_string(capacity_) +
          " requests are already writing the database (or waiting for its lock); nothing was "
          "written, try again",
      "about:blank", /*retry_after_seconds=*/1});
}

int WriteGateCapacity(int threads) {
  return std::max(1, threads / 2);
}

}  // namespace pintag::app
