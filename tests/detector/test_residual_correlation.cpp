// The correlation of neighbouring residuals that the codeword decision counts the lead with:
// measured on residuals whose correlation is known by construction.

#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <vector>

#include "reading/residual_correlation.hpp"

namespace pintag::reading {
namespace {

// Residuals on a cols × rows grid `step` px apart from (x0, y0): independent normal noise, or
// with `pair_sum` the sum of two neighbours' independent noise along x (lag-1 correlation 1/2
// along x, none along y).
std::vector<GridResidual> Grid(int x0, int y0, int cols, int rows, int step, bool pair_sum,
                               int channels) {
  cv::RNG rng(11);
  std::vector<std::vector<std::array<double, 2>>> noise(
      static_cast<std::size_t>(rows), std::vector<std::array<double, 2>>(cols + 1));
  for (auto& row : noise) {
    for (auto& e : row) e = {rng.gaussian(1), channels == 2 ? rng.gaussian(1) : 0};
  }
  std::vector<GridResidual> out;
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < cols; ++x) {
      const auto& e = noise[static_cast<std::size_t>(y)];
      GridResidual g{x0 + step * x, y0 + step * y, e[static_cast<std::size_t>(x)]};
      if (pair_sum) {
        for (std::size_t k = 0; k < 2; ++k) g.r[k] += e[static_cast<std::size_t>(x) + 1][k];
      }
      out.push_back(g);
    }
  }
  return out;
}

TEST(ResidualCorrelation, IndependentResidualsAreUncorrelated) {
  const auto residuals = Grid(3, 5, 80, 60, 1, false, 1);
  const ResidualCorrelation c = NeighbourCorrelation(residuals, cv::Rect(3, 5, 80, 60), /*step=*/1);
  EXPECT_NEAR(c.x, 0, 0.05);
  EXPECT_NEAR(c.y, 0, 0.05);
  EXPECT_NEAR(VarianceInflation(c), 1, 0.25);
}

TEST(ResidualCorrelation, NeighboursSharingNoiseCorrelateByHalfAlongTheirAxisOnly) {
  // Chroma-like: blocks 2 px apart, two channels pooled, the bounds starting on an odd pixel.
  const auto residuals = Grid(7, 4, 60, 50, 2, true, 2);
  const ResidualCorrelation c =
      NeighbourCorrelation(residuals, cv::Rect(7, 4, 120, 100), /*step=*/2);
  EXPECT_NEAR(c.x, 0.5, 0.05);
  EXPECT_NEAR(c.y, 0, 0.05);
  EXPECT_NEAR(VarianceInflation(c), 3, 0.4);  // (1 + 1/2) / (1 - 1/2)
}

TEST(ResidualCorrelation, MissingNeighboursAndEmptyInputCountNothing) {
  // Every other column missing: no pairs along x, so no correlation there.
  std::vector<GridResidual> sparse;
  for (const GridResidual& g : Grid(0, 0, 40, 30, 1, true, 1)) {
    if (g.x % 2 == 0) sparse.push_back(g);
  }
  const ResidualCorrelation c = NeighbourCorrelation(sparse, cv::Rect(0, 0, 40, 30), 1);
  EXPECT_EQ(c.x, 0);
  EXPECT_NEAR(c.y, 0, 0.1);
  const ResidualCorrelation none = NeighbourCorrelation({}, cv::Rect(0, 0, 10, 10), 1);
  EXPECT_EQ(none.x, 0);
  EXPECT_EQ(none.y, 0);
}

TEST(ResidualCorrelation, InflationCountsNoNegativeCorrelationAndCapsNearOne) {
  EXPECT_DOUBLE_EQ(VarianceInflation({0, 0}), 1);
  EXPECT_DOUBLE_EQ(VarianceInflation({-0.4, 0}), 1);
  EXPECT_DOUBLE_EQ(VarianceInflation({0.5, 0.5}), 9);
  const double cap = (1 + kMaxCountedCorrelation) / (1 - kMaxCountedCorrelation);
  EXPECT_DOUBLE_EQ(VarianceInflation({0.999, 0}), cap);
}

}  // namespace
}  // namespace pintag::reading
