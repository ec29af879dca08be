// Stage 5e: corners fitted through the blur model, for small blurred tags whose edge-fitted
// corners are too far off for their cells.

#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "blur_model.hpp"
#include "corner_fit.hpp"
#include "homography.hpp"
#include "synthetic.hpp"

namespace pintag::stage {
namespace {

double MeanCornerError(const Quad& quad, const testing::SyntheticTruth& truth) {
  double sum = 0;
  for (int i = 0; i < 4; ++i) sum += cv::norm(quad[i] - truth.corners[i]) / 4;
  return sum;
}

// Every corner pushed about a pixel off, in a direction that differs per corner and case.
Quad Perturbed(const testing::SyntheticTruth& truth, int case_index) {
  Quad quad;
  for (int i = 0; i < 4; ++i) {
    const double angle = 1.3 * (case_index + 1) + 2.1 * i;
    quad[i] = truth.corners[i] + cv::Point2d(std::cos(angle), std::sin(angle)) * 1.0;
  }
  return quad;
}

testing::SyntheticScene BlurredTag(int key, double square_px, double tilt_deg, double roll_deg,
                                   std::uint64_t seed) {
  testing::SyntheticOptions o;
  o.seed = seed;
  o.blur_sigma = 1.3;
  o.noise_sigma = 2;
  return testing::MakeScene(
      {{.key = key, .square_px = square_px, .tilt_deg = tilt_deg, .roll_deg = roll_deg}}, o);
}

TEST(CornerFit, MovesCornersAPixelOffBackTowardsTheTruth) {
  int case_index = 0;
  double before_sum = 0, after_sum = 0;
  for (const int key : {3, 9999, 21845, 30000}) {
    for (const double tilt : {0.0, 45.0}) {
      const auto scene =
          BlurredTag(key, 34, tilt, 17.0 * case_index, static_cast<std::uint64_t>(case_index) + 5);
      const testing::SyntheticTruth& truth = scene.truth[0];
      const Quad start = Perturbed(truth, case_index);
      const BlurFit fit = FitCellsThroughBlur(scene.bgr, HomographyFromQuad(start));
      ASSERT_TRUE(fit.ok) << "key " << key;
      const CornerFit fitted = FitCornersThroughBlur(scene.bgr, start, fit);
      const double before = MeanCornerError(start, truth);
      const double after = MeanCornerError(fitted.quad, truth);
      EXPECT_TRUE(fitted.moved) << "key " << key << " tilt " << tilt;
      EXPECT_LT(fitted.residual_after, fitted.residual_before);
      EXPECT_LT(after, 0.6 * before) << "key " << key << " tilt " << tilt;
      for (int i = 0; i < 4; ++i) {
        EXPECT_LE(cv::norm(fitted.quad[i] - start[i]), kCornerFitMaxMovePx + 1e-9);
      }
      before_sum += before;
      after_sum += after;
      ++case_index;
    }
  }
  // Over all cases the corners end within a few tenths of a pixel, as the edge fit gets on
  // sharp tags.
  EXPECT_LT(after_sum / case_index, 0.35);
  EXPECT_GT(before_sum / case_index, 0.9);
}

TEST(CornerFit, CorrectCornersStayNearlyPut) {
  const auto scene = BlurredTag(12345, 34, 30, 10, 77);
  const testing::SyntheticTruth& truth = scene.truth[0];
  Quad quad;
  for (int i = 0; i < 4; ++i) quad[i] = truth.corners[i];
  const BlurFit fit = FitCellsThroughBlur(scene.bgr, HomographyFromQuad(quad));
  ASSERT_TRUE(fit.ok);
  const CornerFit fitted = FitCornersThroughBlur(scene.bgr, quad, fit);
  EXPECT_LT(MeanCornerError(fitted.quad, truth), 0.3);
}

TEST(CornerFit, LargeSquaresAndFailedFitsAreLeftAlone) {
  const auto scene = BlurredTag(777, 120, 0, 0, 3);
  Quad quad;
  for (int i = 0; i < 4; ++i) quad[i] = scene.truth[0].corners[i] + cv::Point2d(0.7, -0.4);
  const BlurFit fit = FitCellsThroughBlur(scene.bgr, HomographyFromQuad(quad));
  ASSERT_TRUE(fit.ok);
  const CornerFit large = FitCornersThroughBlur(scene.bgr, quad, fit);
  EXPECT_FALSE(large.moved);
  EXPECT_EQ(large.evaluations, 0);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(large.quad[i], quad[i]);

  const auto small = BlurredTag(777, 34, 0, 0, 3);
  Quad small_quad;
  for (int i = 0; i < 4; ++i) small_quad[i] = small.truth[0].corners[i];
  const CornerFit without_fit = FitCornersThroughBlur(small.bgr, small_quad, BlurFit{});
  EXPECT_FALSE(without_fit.moved);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(without_fit.quad[i], small_quad[i]);
}

}  // namespace
}  // namespace pintag::stage
