// The throttle that keeps a warning repeated by every request (the database that cannot be
// opened) to one line an interval, without losing count of the rest.

#include "pintag/server/log_throttle.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <optional>
#include <string>

namespace pintag::server {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;

TEST(LogThrottle, WritesTheFirstThenOneAnIntervalWithHowManyWereLeftOut) {
  LogThrottle throttle(seconds(10));
  const LogThrottle::Clock::time_point start{};
  EXPECT_EQ(throttle.admit("cannot open database", start), "cannot open database");
  for (int i = 1; i <= 37; ++i) {
    EXPECT_EQ(throttle.admit("cannot open database", start + milliseconds(200) * i), std::nullopt)
        << i;
  }
  EXPECT_EQ(throttle.admit("cannot open database", start + seconds(10) - milliseconds(1)),
            std::nullopt);
  // The interval is over: written, with the 38 left out and how long they took.
  EXPECT_EQ(throttle.admit("cannot open database: disk I/O error", start + seconds(12)),
            "cannot open database: disk I/O error (and 38 more like it in the 12 s before)");
  // The count starts again; one left out is said as one.
  EXPECT_EQ(throttle.admit("cannot open database", start + seconds(13)), std::nullopt);
  EXPECT_EQ(throttle.admit("cannot open database", start + seconds(22)),
            "cannot open database (and 1 more like it in the 10 s before)");
  // After a quiet spell nothing was left out: the line is written as it came.
  EXPECT_EQ(throttle.admit("cannot open database", start + seconds(600)), "cannot open database");
}

TEST(LogThrottle, SaysWhenTheTroublePassedWithWhatWasLeftOutAndWritesTheNextAtOnce) {
  LogThrottle throttle(seconds(10));
  const LogThrottle::Clock::time_point start{};
  // Nothing was written: nothing to settle.
  EXPECT_EQ(throttle.settle("database opens again", start), std::nullopt);
  EXPECT_EQ(throttle.admit("cannot open database", start), "cannot open database");
  EXPECT_EQ(throttle.admit("cannot open database", start + seconds(1)), std::nullopt);
  EXPECT_EQ(throttle.admit("cannot open database", start + seconds(2)), std::nullopt);
  // Successes between failures (descriptors running out now and then) are not the end of it.
  EXPECT_EQ(throttle.settle("database opens again", start + seconds(3)), std::nullopt);
  EXPECT_EQ(throttle.admit("cannot open database", start + seconds(4)), std::nullopt);
  EXPECT_EQ(throttle.settle("database opens again", start + seconds(13)), std::nullopt);
  // An interval with no failure: the trouble has passed.
  EXPECT_EQ(throttle.settle("database opens again", start + seconds(14)),
            "database opens again (3 more like the last warning were left out in the 14 s after "
            "it)");
  EXPECT_EQ(throttle.settle("database opens again", start + seconds(15)), std::nullopt);
  // The next failure, within the interval of the last warning, is written at once.
  EXPECT_EQ(throttle.admit("cannot open database", start + seconds(16)), "cannot open database");
  EXPECT_EQ(throttle.settle("database opens again", start + seconds(30)), "database opens again");
}

}  // namespace
}  // namespace pintag::server
