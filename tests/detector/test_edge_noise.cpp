// Luma samples weighted by the contrast they straddle (reading/edge_noise.hpp): the noise model is
// fitted back from samples whose error grows across edges, and weighting by it brings the free
// model's region colours closer to the truth than counting every sample alike.

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "reading/edge_noise.hpp"
#include "reading/region_fit.hpp"

namespace pintag::reading {
namespace {

// A 40 px tag seen frontally, blurred a little, its regions given colours between dark and bright
// as a tag's luminance is.
struct Scene {
  cv::Rect bounds{30, 30, 40, 40};
  RegionCoverage coverage{cv::Matx33d(40, 0, 30, 0, 40, 30, 0, 0, 1), CoverageBox(bounds)};
  Kernel kernel = MakeKernel(LumaBlur{0.8, 0.8, 0, 0, 1});
  std::array<double, kModelRegions> colours{};

  explicit Scene(std::mt19937& rng) {
    std::uniform_real_distribution<double> element(0.1, 0.5);
    colours[kQuietRegion] = 0.8;
    colours[kBlackRegion] = 0.03;
    for (int r = 2; r < kModelRegions; ++r) colours[static_cast<std::size_t>(r)] = element(rng);
  }

  // Every pixel of the square and a margin, valued by the model plus `error(contrast)`.
  template <typename Error>
  LumaRows observe(Error error) const {
    std::vector<LumaSample> pixels;
    for (int y = bounds.y - 2; y < bounds.br().y + 2; ++y) {
      for (int x = bounds.x - 2; x < bounds.br().x + 2; ++x) pixels.push_back({x, y, 0});
    }
    const LumaRows exact = GatherLumaRows(coverage, pixels, kernel);
    const std::vector<double> contrast = SampleContrast(exact, colours);
    for (std::size_t i = 0; i < pixels.size(); ++i) {
      double predicted = 0;
      for (const LumaRows::Term& t : exact.terms(i)) {
        predicted += t.weight * colours[static_cast<std::size_t>(t.region)];
      }
      pixels[i].value = predicted + error(contrast[i]);
    }
    return GatherLumaRows(coverage, pixels, kernel);
  }

  // Root-mean-square error of `fitted` over the elements' regions.
  double elementError(const std::array<double, kModelRegions>& fitted) const {
    double sum = 0;
    for (int r = 2; r < kModelRegions; ++r) {
      const double d = fitted[static_cast<std::size_t>(r)] - colours[static_cast<std::size_t>(r)];
      sum += d * d;
    }
    return std::sqrt(sum / (kModelRegions - 2));
  }
};

constexpr double kFloor = 1e-3;       // σ 0.03 inside a region
constexpr double kPerContrast = 0.2;  // σ about 0.18 on an edge between 0.8 and 0.03

TEST(EdgeNoise, ContrastIsZeroInsideOneRegionAndLargestAcrossTheSquaresEdge) {
  std::mt19937 rng(7);
  const Scene scene(rng);
  const std::vector<LumaSample> pixels = {{50, 24, 0}, {30, 50, 0}, {50, 50, 0}};
  const std::vector<double> contrast =
      SampleContrast(GatherLumaRows(scene.coverage, pixels, scene.kernel), scene.colours);
  ASSERT_EQ(contrast.size(), 3U);
  EXPECT_EQ(contrast[0], 0.0);  // 6 px out in the quiet zone
  // On the square's left edge: half quiet (0.8), half black (0.03), a variance near 0.385².
  EXPECT_GT(contrast[1], 0.1);
  EXPECT_LT(contrast[2], contrast[1]);  // the tag's centre, among dimmer element colours
}

TEST(EdgeNoise, TheFitRecoversNoiseThatGrowsWithContrast) {
  for (const std::uint32_t seed : {1U, 2U, 3U}) {
    std::mt19937 rng(seed);
    const Scene scene(rng);
    std::normal_distribution<double> unit(0, 1);
    const LumaRows rows = scene.observe(
        [&](double contrast) { return unit(rng) * std::sqrt(kFloor + kPerContrast * contrast); });
    const EdgeNoise fitted = FitEdgeNoise(rows, SampleContrast(rows, scene.colours), scene.colours);
    EXPECT_NEAR(fitted.floor, kFloor, 0.3 * kFloor) << "seed " << seed;
    EXPECT_NEAR(fitted.per_contrast, kPerContrast, 0.25 * kPerContrast) << "seed " << seed;
  }
}

TEST(EdgeNoise, WeightingBringsTheFreeColoursCloserToTheTruth) {
  // Most of a small tag's samples straddle some edge, so the gain is a modest one: counted over
  // twenty scenes, not promised for each.
  double plain_squared = 0, weighted_squared = 0;
  int closer = 0;
  for (std::uint32_t seed = 4; seed < 24; ++seed) {
    std::mt19937 rng(seed);
    const Scene scene(rng);
    std::normal_distribution<double> unit(0, 1);
    const LumaRows rows = scene.observe(
        [&](double contrast) { return unit(rng) * std::sqrt(kFloor + kPerContrast * contrast); });
    // As the reader does it: the free colours first, the noise fitted under them, then again.
    const FreeFit<1> plain = SolveFree(AccumulateLuma(rows));
    ASSERT_TRUE(plain.ok);
    const std::vector<double> contrast = SampleContrast(rows, plain.colour[0]);
    const std::vector<double> weights =
        EdgeNoiseWeights(FitEdgeNoise(rows, contrast, plain.colour[0]), contrast);
    ASSERT_EQ(weights.size(), rows.size());
    const FreeFit<1> weighted = SolveFree(AccumulateLuma(rows, weights));
    ASSERT_TRUE(weighted.ok);
    const double plain_error = scene.elementError(plain.colour[0]);
    const double weighted_error = scene.elementError(weighted.colour[0]);
    plain_squared += plain_error * plain_error;
    weighted_squared += weighted_error * weighted_error;
    closer += weighted_error < plain_error ? 1 : 0;
  }
  EXPECT_LT(weighted_squared, 0.92 * plain_squared);
  EXPECT_GE(closer, 16);
}

TEST(EdgeNoise, SamplesThatFitExactlyAreLeftUnweighted) {
  std::mt19937 rng(8);
  const Scene scene(rng);
  const LumaRows rows = scene.observe([](double) { return 0.0; });
  const EdgeNoise fitted = FitEdgeNoise(rows, SampleContrast(rows, scene.colours), scene.colours);
  EXPECT_EQ(fitted.floor, 0.0);
  EXPECT_TRUE(EdgeNoiseWeights(fitted, SampleContrast(rows, scene.colours)).empty());
  const FreeFit<1> fit = SolveFree(AccumulateLuma(rows));
  ASSERT_TRUE(fit.ok);
  EXPECT_LT(scene.elementError(fit.colour[0]), 0.01);
}

TEST(EdgeNoise, TheSameWeightOnEverySampleLeavesTheFreeColours) {
  // The free fit's ridge pulls towards the samples' mean, which must be their weighted mean.
  std::mt19937 rng(10);
  const Scene scene(rng);
  std::normal_distribution<double> unit(0, 0.02);
  const LumaRows rows = scene.observe([&](double) { return unit(rng); });
  const FreeFit<1> plain = SolveFree(AccumulateLuma(rows));
  const FreeFit<1> quarter =
      SolveFree(AccumulateLuma(rows, std::vector<double>(rows.size(), 0.25)));
  ASSERT_TRUE(plain.ok && quarter.ok);
  for (int r = 0; r < kModelRegions; ++r) {
    EXPECT_NEAR(quarter.colour[0][static_cast<std::size_t>(r)],
                plain.colour[0][static_cast<std::size_t>(r)], 1e-9)
        << "region " << r;
  }
}

TEST(EdgeNoise, AWeightOfOneChangesNothing) {
  std::mt19937 rng(9);
  const Scene scene(rng);
  std::normal_distribution<double> unit(0, 0.02);
  const LumaRows rows = scene.observe([&](double) { return unit(rng); });
  const LumaSystem plain = AccumulateLuma(rows);
  const LumaSystem ones = AccumulateLuma(rows, std::vector<double>(rows.size(), 1.0));
  EXPECT_EQ(plain.ata, ones.ata);
  EXPECT_EQ(plain.aty, ones.aty);
  EXPECT_EQ(plain.yty, ones.yty);
}

}  // namespace
}  // namespace pintag::reading
