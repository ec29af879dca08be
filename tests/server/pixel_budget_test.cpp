// The pixel budget's promises, on real threads: what does not fit waits until room is made, the
// callers are served in the order they came, a photo larger than the whole budget runs alone, and
// nothing is held once every reservation has ended. A thread is known to wait when the budget
// counts it in line; a budget that let it through would never count it, and the test fails.

#include "app/pixel_budget.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <stdexcept>
#include <thread>
#include <vector>

namespace pintag::app {
namespace {

using namespace std::chrono_literals;

// A thread that takes `pixels` from `budget`, says so, and holds them until told to let go.
class Holder {
 public:
  Holder(PixelBudget& budget, std::int64_t pixels)
      : thread_([this, &budget, pixels] {
          PixelBudget::Reservation held = budget.reserve(pixels, &waited_);
          holding_ = true;
          while (!let_go_) std::this_thread::sleep_for(1ms);
        }) {}
  ~Holder() { finish(); }
  Holder(const Holder&) = delete;
  Holder& operator=(const Holder&) = delete;

  bool holding() const { return holding_; }
  bool waited() const { return waited_; }
  /// Waits up to `limit` for the reservation; false if it did not come.
  bool holdsWithin(std::chrono::milliseconds limit) const {
    const auto end = std::chrono::steady_clock::now() + limit;
    while (!holding_ && std::chrono::steady_clock::now() < end) std::this_thread::sleep_for(1ms);
    return holding_;
  }
  void letGo() { let_go_ = true; }
  void finish() {
    letGo();
    if (thread_.joinable()) thread_.join();
  }

 private:
  std::atomic<bool> holding_{false}, let_go_{false};
  bool waited_ = false;  // written before holding_ is set, read after it is seen
  std::thread thread_;
};

// The holders of one test. When it ends (also on a failed assertion) all are told to let go, then
// joined in the order they came: one still waiting is let through by those before it, so a
// failure ends the test instead of hanging it on a thread that waits behind one not yet released.
class Holders {
 public:
  explicit Holders(PixelBudget& budget) : budget_(budget) {}
  ~Holders() {
    for (const std::unique_ptr<Holder>& h : holders_) h->letGo();
    for (const std::unique_ptr<Holder>& h : holders_) h->finish();
  }
  Holders(const Holders&) = delete;
  Holders& operator=(const Holders&) = delete;
  Holder& add(std::int64_t pixels) {
    holders_.push_back(std::make_unique<Holder>(budget_, pixels));
    return *holders_.back();
  }

 private:
  PixelBudget& budget_;
  std::vector<std::unique_ptr<Holder>> holders_;
};

constexpr auto kLongEnough = 10s;  // for something that must happen

// Waits up to kLongEnough until `n` callers wait in `budget`; false if they never do.
bool InLine(const PixelBudget& budget, std::int64_t n) {
  const auto end = std::chrono::steady_clock::now() + kLongEnough;
  while (budget.waiting() != n && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(1ms);
  }
  return budget.waiting() == n;
}

TEST(PixelBudget, WhatFitsIsHeldAtOnceAndReleasedWhenTheReservationEnds) {
  PixelBudget budget(10);
  {
    bool waited = true;
    PixelBudget::Reservation a = budget.reserve(4, &waited);
    EXPECT_FALSE(waited);
    PixelBudget::Reservation b = budget.reserve(6, &waited);
    EXPECT_FALSE(waited);
    EXPECT_EQ(budget.held(), 10);
    PixelBudget::Reservation moved = std::move(a);
    EXPECT_EQ(moved.pixels(), 4);
    EXPECT_EQ(budget.held(), 10);  // a move hands the pixels on, it does not give them back
    moved = PixelBudget::Reservation();
    EXPECT_EQ(budget.held(), 6);
  }
  EXPECT_EQ(budget.held(), 0);
  EXPECT_EQ(budget.peak(), 10);
}

TEST(PixelBudget, WhatDoesNotFitWaitsUntilRoomIsMade) {
  PixelBudget budget(10);
  Holders holders(budget);
  Holder& first = holders.add(6);
  ASSERT_TRUE(first.holdsWithin(kLongEnough));
  Holder& second = holders.add(6);
  ASSERT_TRUE(InLine(budget, 1));
  EXPECT_FALSE(second.holding());
  EXPECT_EQ(budget.held(), 6);
  first.finish();
  ASSERT_TRUE(second.holdsWithin(kLongEnough));
  EXPECT_TRUE(second.waited());
  EXPECT_FALSE(first.waited());
  EXPECT_EQ(budget.peak(), 6);
}

TEST(PixelBudget, ASmallPhotoDoesNotOvertakeALargeOneWaitingBeforeIt) {
  PixelBudget budget(10);
  Holders holders(budget);
  Holder& first = holders.add(6);
  ASSERT_TRUE(first.holdsWithin(kLongEnough));
  Holder& large = holders.add(6);
  ASSERT_TRUE(InLine(budget, 1));
  Holder& small = holders.add(1);  // fits beside the first, but comes later
  ASSERT_TRUE(InLine(budget, 2));
  EXPECT_FALSE(large.holding());
  EXPECT_FALSE(small.holding());
  first.finish();
  ASSERT_TRUE(large.holdsWithin(kLongEnough));
  ASSERT_TRUE(small.holdsWithin(kLongEnough));  // then fits beside the large one
  EXPECT_EQ(budget.held(), 7);
}

TEST(PixelBudget, APhotoLargerThanTheBudgetRunsAloneRatherThanNever) {
  PixelBudget budget(10);
  Holders holders(budget);
  Holder& other = holders.add(3);
  ASSERT_TRUE(other.holdsWithin(kLongEnough));
  Holder& huge = holders.add(25);
  ASSERT_TRUE(InLine(budget, 1));
  EXPECT_FALSE(huge.holding());
  other.finish();
  ASSERT_TRUE(huge.holdsWithin(kLongEnough));
  Holder& after = holders.add(1);
  ASSERT_TRUE(InLine(budget, 1));
  EXPECT_FALSE(after.holding());
  huge.finish();
  ASSERT_TRUE(after.holdsWithin(kLongEnough));
}

TEST(PixelBudget, ManyThreadsNeverHoldMoreThanTheBudgetAndLeaveNothingHeld) {
  PixelBudget budget(100);
  std::atomic<int> done{0};
  std::vector<std::thread> threads;
  threads.reserve(8);
  for (int t = 0; t < 8; ++t) {
    threads.emplace_back([&, t] {
      for (int i = 0; i < 200; ++i) {
        PixelBudget::Reservation r = budget.reserve(10 + (t * 7 + i * 13) % 60);
        EXPECT_LE(budget.held(), 100);
        std::this_thread::yield();
      }
      ++done;
    });
  }
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(done, 8);
  EXPECT_EQ(budget.held(), 0);
  EXPECT_LE(budget.peak(), 100);
  EXPECT_GE(budget.peak(), 10);
}

TEST(PixelBudget, AnEmptyBudgetIsRefused) {
  EXPECT_THROW(PixelBudget(0), std::invalid_argument);
  EXPECT_THROW(PixelBudget(-5), std::invalid_argument);
}

}  // namespace
}  // namespace pintag::app
