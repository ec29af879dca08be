// Stage 4: sub-pixel corners and the homography.

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/calib3d.hpp>
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

TEST(Homography, ShortExtentIsTheNarrowWidthOfARectangleWhateverItsTurn) {
  for (const double turn_deg : {0.0, 30.0, 45.0, 100.0}) {
    const double t = turn_deg * CV_PI / 180;
    const cv::Point2d along(std::cos(t), std::sin(t)), across(-std::sin(t), std::cos(t));
    const cv::Point2d o(200, 150);
    const Quad q = {o, o + 40 * along, o + 40 * along + 16 * across, o + 16 * across};
    EXPECT_NEAR(ShortExtentPx(HomographyFromQuad(q)), 16, 1e-4) << turn_deg;
    EXPECT_NEAR(MeanSidePx(HomographyFromQuad(q)), 28, 1e-4) << turn_deg;
  }
}

TEST(Homography, ShortExtentOfATiltedSquareIsItsSideTimesTheTiltsCosine) {
  // A 50 mm square 1.5 m from a 1500 px camera (50 px frontal) on its optical axis, tilted about
  // axes of several directions in its plane. There the derivative at the centre is the frontal
  // scale times the rotation's first two columns, so the extent is s cos θ exactly: a tolerance
  // of 0.1 % catches a derivative that leaves out the perspective division.
  constexpr double kFocalPx = 1500, kSideM = 0.05, kDistanceM = 1.5;
  for (const double tilt_deg : {0.0, 40.0, 65.0}) {
    for (const double axis_deg : {0.0, 45.0, 80.0}) {
      const double tilt = tilt_deg * CV_PI / 180, axis = axis_deg * CV_PI / 180;
      const cv::Vec3d a(std::cos(axis), std::sin(axis), 0);  // the tilt axis, in the square's plane
      const cv::Matx33d turn = [&] {
        cv::Matx33d r;
        cv::Rodrigues(cv::Vec3d(a * tilt), r);
        return r;
      }();
      Quad q;
      const double uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
      for (int i = 0; i < 4; ++i) {
        const cv::Vec3d p =
            turn * cv::Vec3d((uv[i][0] - 0.5) * kSideM, (uv[i][1] - 0.5) * kSideM, 0) +
            cv::Vec3d(0, 0, kDistanceM);
        q[static_cast<std::size_t>(i)] = {960 + kFocalPx * p[0] / p[2],
                                          540 + kFocalPx * p[1] / p[2]};
      }
      const double frontal = kFocalPx * kSideM / kDistanceM;
      EXPECT_NEAR(ShortExtentPx(HomographyFromQuad(q)), frontal * std::cos(tilt), 1e-3 * frontal)
          << tilt_deg << "° about " << axis_deg << "°";
    }
  }
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
