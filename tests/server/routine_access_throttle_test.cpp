// The throttle that keeps a replica's snapshot polls, answered 304 once a second, to one access
// line a minute for each replica, without losing count of the rest.

#include "pintag/server/routine_access_throttle.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <optional>
#include <string>

namespace pintag::server {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;

TEST(RoutineAccessThrottle, WritesAKindOnceAnIntervalSayingHowManyWereLeftOut) {
  RoutineAccessThrottle throttle(seconds(60));
  const RoutineAccessThrottle::Clock::time_point start{};
  EXPECT_EQ(throttle.admit("replica-a 304", start), 0U);
  for (int i = 1; i <= 59; ++i) {
    EXPECT_EQ(throttle.admit("replica-a 304", start + seconds(i)), std::nullopt) << i;
  }
  // Another kind (another replica, or the same one answered otherwise) has its own interval.
  EXPECT_EQ(throttle.admit("replica-b 304", start + seconds(30)), 0U);
  EXPECT_EQ(throttle.admit("replica-b 304", start + seconds(31)), std::nullopt);
  // The interval is over: written, with the 59 left out; the count starts again.
  EXPECT_EQ(throttle.admit("replica-a 304", start + seconds(60)), 59U);
  EXPECT_EQ(throttle.admit("replica-a 304", start + seconds(61)), std::nullopt);
  EXPECT_EQ(throttle.admit("replica-a 304", start + seconds(120) - milliseconds(1)), std::nullopt);
  EXPECT_EQ(throttle.admit("replica-a 304", start + seconds(120)), 2U);
  EXPECT_EQ(throttle.admit("replica-b 304", start + seconds(95)), 1U);
  // After a quiet spell nothing was left out.
  EXPECT_EQ(throttle.admit("replica-a 304", start + seconds(900)), 0U);
}

TEST(RoutineAccessThrottle, ForgetsOldKindsPastItsBoundAndThenWritesRatherThanGrow) {
  RoutineAccessThrottle throttle(seconds(60), 2);
  const RoutineAccessThrottle::Clock::time_point start{};
  EXPECT_EQ(throttle.admit("a", start), 0U);
  EXPECT_EQ(throttle.admit("b", start + seconds(10)), 0U);
  // Full, and no kind's interval is over: a third kind is written every time, never tracked.
  EXPECT_EQ(throttle.admit("c", start + seconds(20)), 0U);
  EXPECT_EQ(throttle.admit("c", start + seconds(21)), 0U);
  EXPECT_EQ(throttle.admit("a", start + seconds(22)), std::nullopt);
  // "a" is forgotten once its interval is over, which makes room for "c".
  EXPECT_EQ(throttle.admit("c", start + seconds(65)), 0U);
  EXPECT_EQ(throttle.admit("c", start + seconds(66)), std::nullopt);
  EXPECT_EQ(throttle.admit("b", start + seconds(67)), std::nullopt);
}

}  // namespace
}  // namespace pintag::server
