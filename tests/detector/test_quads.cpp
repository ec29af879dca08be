// Stage 3a: the tag is one dark quad in min(R, G, B) inside its quiet zone.

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <random>

#include "candidates/quads.hpp"
#include "synthetic.hpp"

namespace pintag::stage {
namespace {

TEST(Quads, FindsTheSquareOfAWarpedTagOnDarkAndLightGround) {
  for (std::uint64_t seed : {1, 2, 3, 4}) {
    testing::SyntheticOptions o;
    o.seed = seed;
    const auto scene = testing::MakeScene(
        {{.key = 100, .square_px = 120, .tilt_deg = 40, .tilt_axis_deg = 30, .roll_deg = 20}}, o);
    const cv::Rect roi(330, 120, 300, 300);
    const auto quads = FindQuads(MinChannel(scene.bgr, roi), roi.tl(), 20);
    int matched = 0;
    for (const Quad& q : quads) {
      EXPECT_GT(SignedArea2(q), 0);  // clockwise on screen
      double worst = 0;
      for (int i = 0; i < 4; ++i) {
        double best = 1e9;
        for (int j = 0; j < 4; ++j)
          best = std::min(best, cv::norm(q[j] - scene.truth[0].corners[i]));
        worst = std::max(worst, best);
      }
      matched += worst < 2.5;
    }
    EXPECT_EQ(matched, 1) << "seed " << seed;
  }
}

TEST(Quads, SameSquareWhicheverCornerComesFirstAndOnlyWithinTheTolerance) {
  const Quad q = {cv::Point2d(10, 10), {40, 12}, {38, 41}, {9, 39}};
  for (int turn = 0; turn < 4; ++turn) {
    Quad turned;
    for (std::size_t i = 0; i < 4; ++i) turned[i] = q[(i + turn) % 4] + cv::Point2d(0.1, -0.1);
    EXPECT_TRUE(SameSquare(q, turned, 0.25)) << turn;
    turned[2].x += 0.3;  // one corner beyond the tolerance
    EXPECT_FALSE(SameSquare(q, turned, 0.25)) << turn;
  }
  const Quad mirrored = {q[0], q[3], q[2], q[1]};  // the other winding is another outline
  EXPECT_FALSE(SameSquare(q, mirrored, 0.25));
}

TEST(Quads, SignedAreaIsPositiveClockwise) {
  const Quad q = {cv::Point2d(0, 0), {1, 0}, {1, 1}, {0, 1}};
  EXPECT_GT(SignedArea2(q), 0);
}

}  // namespace
}  // namespace pintag::stage

namespace pintag::stage {
namespace {

TEST(Quads, CloseGapsAsOpenCvClosesWithAThreeByThreeSquare) {
  std::mt19937 rng(1127);
  for (int i = 0; i < 500; ++i) {
    const int width = 1 + static_cast<int>(rng() % 70), height = 1 + static_cast<int>(rng() % 40);
    cv::Mat image(height + 2, width + 3, CV_8U);
    for (int y = 0; y < image.rows; ++y) {
      for (int x = 0; x < image.cols; ++x) image.at<std::uint8_t>(y, x) = rng() % 3 ? 255 : 0;
    }
    // A region of a larger image: rows not continuous in memory, closed in place.
    cv::Mat binary = image(cv::Rect(1, 1, width, height));
    cv::Mat expected;
    cv::morphologyEx(binary.clone(), expected, cv::MORPH_CLOSE,
                     cv::getStructuringElement(cv::MORPH_RECT, {3, 3}));
    CloseGaps3x3(binary);
    ASSERT_EQ(cv::countNonZero(binary != expected), 0) << width << " x " << height;
  }
  // Gaps of one and two pixels across a bar are bridged; one of three is not.
  cv::Mat bars(5, 16, CV_8U, cv::Scalar(255));
  bars.col(2).setTo(0);
  bars.colRange(5, 7).setTo(0);
  bars.colRange(10, 13).setTo(0);
  CloseGaps3x3(bars);
  EXPECT_EQ(cv::countNonZero(bars.colRange(0, 10)), 50);
  EXPECT_EQ(cv::countNonZero(bars.col(11)), 0);
}

}  // namespace
}  // namespace pintag::stage
