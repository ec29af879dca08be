// The report's comparison of PinTag's recall with ArUco's (src/recall_comparison.hpp): the
// number of bins an equally good detector trails in by chance, and the paired difference with
// its interval and exact test, each checked against cases worked by hand and against simulation.

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "recall_comparison.hpp"

namespace pintag::bench {
namespace {

// Uniform in [0, 1) from the engine's raw output, which the standard fixes for mt19937.
double Uniform(std::mt19937& rng) {
  return static_cast<double>(rng()) / 4294967296.0;
}

int Draw(std::mt19937& rng, int tags, double rate) {
  int found = 0;
  for (int i = 0; i < tags; ++i) found += Uniform(rng) < rate ? 1 : 0;
  return found;
}

TEST(BinsBehindByChance, NoBinsNoneBehind) {
  const BinsBehindByChance chance = ChanceOfBinsBehind({});
  EXPECT_DOUBLE_EQ(chance.expected, 0);
  ASSERT_EQ(chance.probability.size(), 1U);
  EXPECT_DOUBLE_EQ(chance.atMost(0), 1);
}

TEST(BinsBehindByChance, TwoBinsOfTwoTagsAtEvenOddsByHand) {
  const std::vector<BinTally> two_coins{{2, 1}, {2, 1}};
  // Each bin of two tags at ½: counts 0, 1, 2 with ¼, ½, ¼; a tie ⅜, so behind (1 − ⅜) / 2.
  const BinsBehindByChance chance = ChanceOfBinsBehind(two_coins);
  const double b = 5.0 / 16;
  EXPECT_NEAR(chance.expected, 2 * b, 1e-12);
  ASSERT_EQ(chance.probability.size(), 3U);
  EXPECT_NEAR(chance.probability[0], (1 - b) * (1 - b), 1e-12);
  EXPECT_NEAR(chance.probability[1], 2 * b * (1 - b), 1e-12);
  EXPECT_NEAR(chance.probability[2], b * b, 1e-12);
  EXPECT_NEAR(chance.atMost(1), 1 - b * b, 1e-12);
  EXPECT_NEAR(chance.atMost(5), 1, 1e-12);
}

TEST(BinsBehindByChance, BinsEveryoneFindsOrEveryoneMissesAreNeverBehind) {
  const std::vector<BinTally> bins{{16, 16}, {16, 0}, {0, 0}};
  const BinsBehindByChance chance = ChanceOfBinsBehind(bins);
  EXPECT_DOUBLE_EQ(chance.expected, 0);
  EXPECT_DOUBLE_EQ(chance.atMost(0), 1);
}

// A bin the reference found whole: with its observed rate of 1 no detector can trail it there;
// smoothed, the rate is 16.5 / 17 and trailing is possible, as it is for a detector that misses.
TEST(BinsBehindByChance, ASmoothedRateLetsABinFoundWholeBeTrailedIn) {
  const std::vector<BinTally> whole{{16, 16}};
  EXPECT_DOUBLE_EQ(ChanceOfBinsBehind(whole, BinRate::kObserved).expected, 0);
  const double p = 16.5 / 17;
  double tie = 0;
  for (int k = 0; k <= 16; ++k) {
    const double f = std::exp(std::lgamma(17.0) - std::lgamma(k + 1.0) - std::lgamma(17.0 - k) +
                              k * std::log(p) + (16 - k) * std::log(1 - p));
    tie += f * f;
  }
  EXPECT_NEAR(ChanceOfBinsBehind(whole, BinRate::kSmoothed).expected, (1 - tie) / 2, 1e-12);
  EXPECT_GT(ChanceOfBinsBehind(whole, BinRate::kSmoothed).expected, 0.01);
}

TEST(BinsBehindByChance, AgreesWithSimulatedSweeps) {
  // Thirty bins of sixteen tags with rates from 0.3 to 1, as a sweep's target bins look.
  std::vector<BinTally> bins;
  bins.reserve(30);
  for (int i = 0; i < 30; ++i) bins.push_back({16, 5 + (i * 11) % 12});
  const BinsBehindByChance chance = ChanceOfBinsBehind(bins);
  std::mt19937 rng(20261201);
  constexpr int kSweeps = 20000;
  std::vector<int> count(bins.size() + 1, 0);
  double sum = 0;
  for (int s = 0; s < kSweeps; ++s) {
    int behind = 0;
    for (const BinTally& bin : bins) {
      const double rate = static_cast<double>(bin.found) / bin.tags;
      const int detector = Draw(rng, bin.tags, rate);
      const int reference = Draw(rng, bin.tags, rate);
      behind += detector < reference ? 1 : 0;
    }
    ++count[static_cast<std::size_t>(behind)];
    sum += behind;
  }
  EXPECT_NEAR(chance.expected, sum / kSweeps, 0.05);
  for (std::size_t k = 0; k < count.size(); ++k) {
    const double p = chance.probability[k];
    const double seen = static_cast<double>(count[k]) / kSweeps;
    EXPECT_NEAR(seen, p, 4 * std::sqrt(p * (1 - p) / kSweeps) + 1e-4) << k << " bins behind";
  }
}

TEST(RecallDifference, McNemarsExactTestByHand) {
  // Ten discordant poses all one way: 2 × ½¹⁰.
  const RecallDifference all_one_way = CompareRecall({80, 10, 0, 10});
  EXPECT_NEAR(all_one_way.p_value, 2.0 / 1024, 1e-12);
  EXPECT_NEAR(all_one_way.points, 10, 1e-12);
  // 100 poses, the net count's variance 10 − 10² / 100 = 9, so the difference's standard error
  // is 3 / 100: 10 ± 1.96 × 3 points.
  EXPECT_NEAR(all_one_way.low, 10 - 1.959964 * 3, 1e-9);
  EXPECT_NEAR(all_one_way.high, 10 + 1.959964 * 3, 1e-9);
  // Eight against two: 2 × (1 + 10 + 45) / 1024.
  EXPECT_NEAR(CompareRecall({50, 2, 8, 40}).p_value, 2 * 56.0 / 1024, 1e-12);
  EXPECT_NEAR(CompareRecall({50, 2, 8, 40}).points, -6, 1e-12);
  // Even splits, and no discordant pose at all, show no difference.
  EXPECT_DOUBLE_EQ(CompareRecall({50, 5, 5, 40}).p_value, 1);
  const RecallDifference none = CompareRecall({60, 0, 0, 40});
  EXPECT_DOUBLE_EQ(none.p_value, 1);
  EXPECT_DOUBLE_EQ(none.low, 0);
  EXPECT_DOUBLE_EQ(none.high, 0);
}

TEST(RecallDifference, SwappingTheDetectorsMirrorsTheInterval) {
  const RecallDifference a = CompareRecall({300, 12, 30, 138});
  const RecallDifference b = CompareRecall({300, 30, 12, 138});
  EXPECT_NEAR(a.points, -b.points, 1e-12);
  EXPECT_NEAR(a.low, -b.high, 1e-12);
  EXPECT_NEAR(a.high, -b.low, 1e-12);
  EXPECT_NEAR(a.p_value, b.p_value, 1e-12);
  EXPECT_LT(a.high, 0);
}

TEST(RecallDifference, TheIntervalCoversTheTrueDifferenceNineteenTimesInTwenty) {
  // Poses where only the first detector finds the tag with 4 %, only the second with 9 %: a true
  // difference of −5 points, sampled 480 poses at a time as a sweep's target bins are.
  std::mt19937 rng(42);
  constexpr int kSamples = 4000;
  int covered = 0;
  for (int s = 0; s < kSamples; ++s) {
    PairedOutcomes o;
    for (int i = 0; i < 480; ++i) {
      const double u = Uniform(rng);
      if (u < 0.04) {
        ++o.only_first;
      } else if (u < 0.13) {
        ++o.only_second;
      } else if (u < 0.85) {
        ++o.both;
      } else {
        ++o.neither;
      }
    }
    const RecallDifference d = CompareRecall(o);
    covered += d.low <= -5 && -5 <= d.high ? 1 : 0;
  }
  EXPECT_NEAR(static_cast<double>(covered) / kSamples, 0.95, 0.015);
}

}  // namespace
}  // namespace pintag::bench
