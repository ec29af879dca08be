// The research tools' option values are read strictly: a typo must end the run, not pick the
// held-out world, seed 0 or a clamped count.
#include <gtest/gtest.h>

#include "cli_values.hpp"

namespace pintag::bench {
namespace {

TEST(CliValues, WorldsAreNamedExactly) {
  EXPECT_EQ(ParseWorld("tuning"), scene::World::kTuning);
  EXPECT_EQ(ParseWorld("held-out"), scene::World::kHeldOut);
  EXPECT_EQ(ParseWorld("blind"), scene::World::kBlind);
  EXPECT_FALSE(ParseWorld("tunning"));
  EXPECT_FALSE(ParseWorld("Tuning"));
  EXPECT_FALSE(ParseWorld(""));
  EXPECT_FALSE(ParseWorld("Blind"));
}

TEST(CliValues, SeedsAreWholeDecimalNumbers) {
  EXPECT_EQ(ParseSeed("0"), 0U);
  EXPECT_EQ(ParseSeed("111"), 111U);
  EXPECT_EQ(ParseSeed("9999999999999999999"), 9999999999999999999ULL);
  EXPECT_FALSE(ParseSeed("abc"));
  EXPECT_FALSE(ParseSeed("12x"));
  EXPECT_FALSE(ParseSeed("-1"));
  EXPECT_FALSE(ParseSeed(""));
  EXPECT_FALSE(ParseSeed("10000000000000000000"));  // 20 digits
}

TEST(CliValues, IntegersInRangeAreTakenWhole) {
  EXPECT_EQ(IntegerOrExit("tool", "--n", "1", 1, 4), 1);
  EXPECT_EQ(IntegerOrExit("tool", "--n", "4", 1, 4), 4);
  EXPECT_EQ(IntegerOrExit("tool", "--n", "-3", -5, 4), -3);
  EXPECT_DOUBLE_EQ(NumberOrExit("tool", "--x", "0.6", 0, 10), 0.6);
  EXPECT_DOUBLE_EQ(NumberOrExit("tool", "--x", "10", 0, 10), 10);
}

TEST(CliValuesDeathTest, AnythingElseEndsTheRunWithStatusTwoNamingTheOption) {
  const auto exits = testing::ExitedWithCode(2);
  EXPECT_EXIT(IntegerOrExit("tool", "--draws", "abc", 1, 4), exits, "tool: --draws .*\"abc\"");
  EXPECT_EXIT(IntegerOrExit("tool", "--draws", "0", 1, 4), exits, "from 1 to 4");
  EXPECT_EXIT(IntegerOrExit("tool", "--draws", "5", 1, 4), exits, "--draws");
  EXPECT_EXIT(IntegerOrExit("tool", "--draws", "2x", 1, 4), exits, "--draws");
  EXPECT_EXIT(IntegerOrExit("tool", "--draws", "", 1, 4), exits, "--draws");
  EXPECT_EXIT(IntegerOrExit("tool", "--draws", "99999999999", 1, 4), exits, "--draws");
  EXPECT_EXIT(NumberOrExit("tool", "--jitter", "nan", 0, 10), exits, "--jitter");
  EXPECT_EXIT(NumberOrExit("tool", "--jitter", "0.5px", 0, 10), exits, "--jitter");
  EXPECT_EXIT(NumberOrExit("tool", "--jitter", "-0.1", 0, 10), exits, "--jitter");
  EXPECT_EXIT(WorldOrExit("tool", "tunning"), exits, "--world");
  EXPECT_EXIT(SeedOrExit("tool", "abc"), exits, "--seed");
}

}  // namespace
}  // namespace pintag::bench
