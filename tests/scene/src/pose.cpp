// Camera and pose helpers: intrinsics, MakePose, projection, viewing angle.

#include <algorithm>
#include <cmath>
#include <numbers>

#include "pintag/scene/scene.hpp"

namespace pintag::scene {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;

/// Rotation by `angle` radians about the unit vector `axis` (Rodrigues).
cv::Matx33d AxisAngle(cv::Vec3d axis, double angle) {
  const double c = std::cos(angle), s = std::sin(angle), k = 1 - c;
  const double x = axis[0], y = axis[1], z = axis[2];
  return {c + x * x * k,     x * y * k - z * s, x * z * k + y * s,  //
          y * x * k + z * s, c + y * y * k,     y * z * k - x * s,  //
          z * x * k - y * s, z * y * k + x * s, c + z * z * k};
}

}  // namespace

cv::Matx33d CameraMatrix(const Camera& camera) {
  return {camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1};
}

Pose MakePose(const Camera& camera, cv::Point2d centre_px, double distance_m, double tilt_deg,
              double tilt_axis_deg, double roll_deg) {
  const cv::Vec3d ray = cv::normalize(
      cv::Vec3d((centre_px.x - camera.cx) / camera.fx, (centre_px.y - camera.cy) / camera.fy, 1.0));
  // R0 turns the optical axis onto the ray, so tilt 0 is frontal wherever the square is.
  const cv::Vec3d z_axis(0, 0, 1);
  const cv::Vec3d cross = z_axis.cross(ray);
  const double sin_angle = cv::norm(cross);
  const double cos_angle = std::clamp(z_axis.dot(ray), -1.0, 1.0);
  const cv::Matx33d to_ray =
      sin_angle < 1e-12 ? cv::Matx33d::eye()
                        : AxisAngle(cross * (1.0 / sin_angle), std::atan2(sin_angle, cos_angle));
  const double phi = tilt_axis_deg * kDegToRad;
  const cv::Matx33d tilt =
      AxisAngle(cv::Vec3d(std::cos(phi), std::sin(phi), 0), tilt_deg * kDegToRad);
  const cv::Matx33d roll = AxisAngle(z_axis, roll_deg * kDegToRad);
  Pose pose;
  pose.rotation = to_ray * tilt * roll;
  pose.translation = ray * distance_m;
  return pose;
}

double DistanceForSquarePx(const Camera& camera, double square_px, double side_m) {
  return camera.fx * side_m / square_px;
}

double ViewTiltDeg(const Pose& pose) {
  const cv::Vec3d normal(pose.rotation(0, 2), pose.rotation(1, 2), pose.rotation(2, 2));
  const double t = cv::norm(pose.translation);
  if (t <= 0) return 0;
  const double c = std::clamp(std::abs(normal.dot(pose.translation)) / t, 0.0, 1.0);
  return std::acos(c) / kDegToRad;
}

cv::Point2d ProjectPoint(const Camera& camera, const Pose& pose, const cv::Vec3d& model_point_m) {
  const cv::Vec3d p = pose.rotation * model_point_m + pose.translation;
  return {camera.fx * p[0] / p[2] + camera.cx, camera.fy * p[1] / p[2] + camera.cy};
}

cv::Point2d ProjectSquarePoint(const MarkerTruth& truth, cv::Point2d square_point) {
  const cv::Vec3d p = truth.homography * cv::Vec3d(square_point.x, square_point.y, 1.0);
  return {p[0] / p[2], p[1] / p[2]};
}

}  // namespace pintag::scene
