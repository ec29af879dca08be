#include "app/pixel_budget.hpp"

#include <algorithm>
#include <stdexcept>
#include <utility>

namespace pintag::app {

PixelBudget::PixelBudget(std::int64_t capacity) : capacity_(capacity) {
  if (capacity <= 0) throw std::invalid_argument("a pixel budget must be positive");
}

PixelBudget::Reservation PixelBudget::reserve(std::int64_t pixels, bool* waited) {
  pixels = std::max<std::int64_t>(pixels, 0);
  std::unique_lock lock(mutex_);
  const std::uint64_t ticket = next_ticket_++;
  const auto my_turn = [&] {
    return ticket == serving_ && (held_ == 0 || pixels <= capacity_ - held_);
  };
  const bool at_once = my_turn();
  if (!at_once) turn_.wait(lock, my_turn);
  if (waited != nullptr) *waited = !at_once;
  held_ += pixels;
  peak_ = std::max(peak_, held_);
  ++serving_;
  // The next in line may fit beside this one.
  turn_.notify_all();
  return {this, pixels};
}

void PixelBudget::release(std::int64_t pixels) {
  {
    const std::lock_guard lock(mutex_);
    held_ -= pixels;
  }
  turn_.notify_all();
}

std::int64_t PixelBudget::held() const {
  const std::lock_guard lock(mutex_);
  return held_;
}

std::int64_t PixelBudget::waiting() const {
  const std::lock_guard lock(mutex_);
  return static_cast<std::int64_t>(next_ticket_ - serving_);
}

std::int64_t PixelBudget::peak() const {
  const std::lock_guard lock(mutex_);
  return peak_;
}

PixelBudget::Reservation::Reservation(Reservation&& other) noexcept
    : budget_(std::exchange(other.budget_, nullptr)), pixels_(std::exchange(other.pixels_, 0)) {}

PixelBudget::Reservation& PixelBudget::Reservation::operator=(Reservation&& other) noexcept {
  if (this != &other) {
    if (budget_ != nullptr) budget_->release(pixels_);
    budget_ = std::exchange(other.budget_, nullptr);
    pixels_ = std::exchange(other.pixels_, 0);
  }
  return *this;
}

PixelBudget::Reservation::~Reservation() {
  if (budget_ != nullptr) budget_->release(pixels_);
}

}  // namespace pintag::app
