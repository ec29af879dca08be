// Stage 4: sub-pixel corners and the homography.

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <utility>
#include <vector>

#include "homography.hpp"
#include "synthetic.hpp"

namespace pintag::stage {
namespace {

TEST(Homography, MapsTheUnitSquareToTheQuad) {
  const Quad q = {cv::Point2d(10, 20), {110, 25}, {105, 130}, {12, 118}};
  const cv::Matx33d h = HomographyFromQuad(q);
  const double uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (int i = 0; i < 4; ++i) EXPECT_LT(cv::norm(Apply(h, uv[i][0], uv[i][1]) - q[i]), 1e-3);
  const Quad r = RotateQuad(q, 1);
  EXPECT_EQ(r[0], q[1]);
  EXPECT_EQ(r[3], q[0]);
}

TEST(Homography, RefinesRoughCornersToASmallFractionOfAPixel) {
  testing::SyntheticOptions o;
  o.blur_sigma = 0.8;
  const auto scene = testing::MakeScene(
      {{.key = 3, .square_px = 100, .tilt_deg = 35, .tilt_axis_deg = 70, .roll_deg = 12}}, o);
  const auto& truth = scene.truth[0].corners;
  Quad quad;
  const cv::Point2d offsets[4] = {{1.2, -0.8}, {-1, 1}, {0.7, 1.3}, {-1.4, -0.6}};
  for (int i = 0; i < 4; ++i) quad[i] = truth[i] + offsets[i];
  const cv::Rect roi(300, 100, 360, 340);
  const cv::Mat dark = [&] {
    cv::Mat m(roi.size(), CV_8U);
    for (int y = 0; y < roi.height; ++y) {
      for (int x = 0; x < roi.width; ++x) {
        const cv::Vec3b p = scene.bgr.at<cv::Vec3b>(roi.y + y, roi.x + x);
        m.at<std::uint8_t>(y, x) = std::min({p[0], p[1], p[2]});
      }
    }
    return m;
  }();
  ASSERT_TRUE(RefineCorners(dark, roi.tl(), &quad));
  for (int i = 0; i < 4; ++i) EXPECT_LT(cv::norm(quad[i] - truth[i]), 0.15) << i;
}

// A steep view on dark ground: across the tilt the quiet zone is a light band about 2 px wide
// with dark ground beyond, nearer than the edge search reaches. The white level must be the
// band, not the ground at the far end of each profile.
TEST(Homography, RefinesASteepSquareWhoseQuietZoneIsAThinBandOnDarkGround) {
  constexpr int kSupersample = 8;
  const cv::Point2d origin(20.3, 30.7);
  const double width = 64, height = 14;  // a square seen at about 77°
  const auto polygon = [&](double grow_x, double grow_y) {
    std::vector<cv::Point> points;
    for (const auto& [x, y] :
         {std::pair{-grow_x, -grow_y}, std::pair{width + grow_x, -grow_y},
          std::pair{width + grow_x, height + grow_y}, std::pair{-grow_x, height + grow_y}}) {
      points.emplace_back(cvRound((origin.x + x + 0.5) * kSupersample),
                          cvRound((origin.y + y + 0.5) * kSupersample));
    }
    return points;
  };
  // Linear light (ground, quiet zone, square), blurred there as a lens does, then sRGB-encoded.
  cv::Mat big(80 * kSupersample, 110 * kSupersample, CV_32F, cv::Scalar(0.005));
  cv::fillConvexPoly(big, polygon(0.15 * width, 0.15 * height), cv::Scalar(0.55));
  cv::fillConvexPoly(big, polygon(0, 0), cv::Scalar(0.007));
  cv::Mat linear;
  cv::resize(big, linear, {110, 80}, 0, 0, cv::INTER_AREA);
  cv::GaussianBlur(linear, linear, {0, 0}, 0.7);
  cv::Mat dark(linear.size(), CV_8U);
  for (int y = 0; y < dark.rows; ++y) {
    for (int x = 0; x < dark.cols; ++x) {
      const double v = linear.at<float>(y, x);
      const double code = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
      dark.at<std::uint8_t>(y, x) = cv::saturate_cast<std::uint8_t>(255 * code);
    }
  }
  const Quad truth = {origin, origin + cv::Point2d(width, 0), origin + cv::Point2d(width, height),
                      origin + cv::Point2d(0, height)};
  Quad quad = truth;
  const cv::Point2d offsets[4] = {{1.0, -0.6}, {-0.8, 0.7}, {0.6, 0.8}, {-0.9, -0.5}};
  for (int i = 0; i < 4; ++i) quad[i] += offsets[i];
  ASSERT_TRUE(RefineCorners(dark, {0, 0}, &quad));
  // A band this thin is lower than the white once blurred, and so is its halfway level.
  for (int i = 0; i < 4; ++i) EXPECT_LT(cv::norm(quad[i] - truth[i]), 0.35) << i;
}

}  // namespace
}  // namespace pintag::stage
