// Stage 7: both planar solutions, refined; the right one wins.

#include <gtest/gtest.h>

#include <numbers>
#include <opencv2/calib3d.hpp>

#include "pose/pose.hpp"

namespace pintag::stage {
namespace {

TEST(Pose, RecoversAKnownPose) {
  const CameraIntrinsics camera{1000, 1000, 640, 360, {}};
  const cv::Vec3d rvec(0.5, -0.3, 0.4), tvec(0.05, -0.02, 0.6);
  const double h = 0.025;
  const std::vector<cv::Point3d> model = {{-h, -h, 0}, {h, -h, 0}, {h, h, 0}, {-h, h, 0}};
  std::vector<cv::Point2d> image;
  const cv::Matx33d k(1000, 0, 640, 0, 1000, 360, 0, 0, 1);
  cv::projectPoints(model, rvec, tvec, k, cv::noArray(), image);
  std::array<cv::Point2d, 4> corners;
  std::copy(image.begin(), image.end(), corners.begin());
  const PoseResult p = EstimatePose(corners, camera, 0.05);
  ASSERT_TRUE(p.ok);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(p.best.translation[i], tvec[i], 1e-6);
    EXPECT_NEAR(p.best.rotation_vector[i], rvec[i], 1e-6);
  }
  EXPECT_NEAR(p.best.distance_m, cv::norm(tvec), 1e-6);
  EXPECT_LT(p.best.reprojection_error_px, 1e-6);
  // The quaternion is the same rotation.
  const auto& q = p.best.quaternion;
  EXPECT_NEAR(2 * std::acos(q[0]), cv::norm(rvec), 1e-6);
  EXPECT_GE(p.alternative.reprojection_error_px, p.best.reprojection_error_px);
}

TEST(Pose, FrontalSmallTagIsFlaggedAmbiguous) {
  // A small frontal square: the two planar solutions fit equally (the classic flip).
  const CameraIntrinsics camera{1000, 1000, 640, 360, {}};
  const std::array<cv::Point2d, 4> corners = {
      cv::Point2d(630, 350), {650, 350}, {650, 370}, {630, 370}};
  const PoseResult p = EstimatePose(corners, camera, 0.05);
  ASSERT_TRUE(p.ok);
  EXPECT_TRUE(p.ambiguous);
  EXPECT_NEAR(p.best.distance_m, 2.5, 0.01);
}

}  // namespace
}  // namespace pintag::stage
