// Stage 4: sub-pixel corners and the homography.

#include <gtest/gtest.h>

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
    for (int y = 0; y < roi.height; ++y)
      for (int x = 0; x < roi.width; ++x) {
        const cv::Vec3b p = scene.bgr.at<cv::Vec3b>(roi.y + y, roi.x + x);
        m.at<std::uint8_t>(y, x) = std::min({p[0], p[1], p[2]});
      }
    return m;
  }();
  ASSERT_TRUE(RefineCorners(dark, roi.tl(), &quad));
  for (int i = 0; i < 4; ++i) EXPECT_LT(cv::norm(quad[i] - truth[i]), 0.15) << i;
}

}  // namespace
}  // namespace pintag::stage
