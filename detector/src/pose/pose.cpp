#include "pose/pose.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <vector>

namespace pintag::stage {
namespace {

// Both errors below this, or the worse within this factor of the better: no clear winner.
constexpr double kAmbiguousRatio = 1.5;

double RmsError(const std::vector<cv::Point3d>& model, const std::vector<cv::Point2d>& image,
                const cv::Vec3d& rvec, const cv::Vec3d& tvec, const cv::Mat& k,
                const cv::Mat& dist) {
  std::vector<cv::Point2d> projected;
  cv::projectPoints(model, rvec, tvec, k, dist, projected);
  double sum = 0;
  for (std::size_t i = 0; i < image.size(); ++i) {
    const cv::Point2d d = projected[i] - image[i];
    sum += d.dot(d);
  }
  return std::sqrt(sum / image.size());
}

}  // namespace

PoseSolution MakeSolution(const cv::Vec3d& rvec, const cv::Vec3d& tvec, double error_px) {
  PoseSolution s;
  cv::Matx33d r;
  cv::Rodrigues(rvec, r);
  Eigen::Matrix3d m;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      s.rotation[i][j] = r(i, j);
      m(i, j) = r(i, j);
    }
    s.rotation_vector[i] = rvec[i];
    s.translation[i] = tvec[i];
  }
  Eigen::Quaterniond q(m);
  q.normalize();
  if (q.w() < 0) q.coeffs() *= -1;
  s.quaternion = {q.w(), q.x(), q.y(), q.z()};
  s.distance_m = cv::norm(tvec);
  s.reprojection_error_px = error_px;
  return s;
}

PoseResult EstimatePose(const std::array<cv::Point2d, 4>& corners, const CameraIntrinsics& camera,
                        double tag_size_m) {
  PoseResult result;
  const double h = tag_size_m / 2;
  const std::vector<cv::Point3d> model = {{-h, -h, 0}, {h, -h, 0}, {h, h, 0}, {-h, h, 0}};
  const std::vector<cv::Point2d> image(corners.begin(), corners.end());
  const cv::Mat k =
      (cv::Mat_<double>(3, 3) << camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
  const cv::Mat dist =
      camera.distortion.empty() ? cv::Mat() : cv::Mat(camera.distortion, true).reshape(1, 1);
  std::vector<cv::Mat> rvecs, tvecs;
  try {
    cv::solvePnPGeneric(model, image, k, dist, rvecs, tvecs, false, cv::SOLVEPNP_IPPE);
  } catch (const cv::Exception&) {
    return result;
  }
  if (rvecs.empty()) return result;
  std::vector<std::pair<double, PoseSolution>> solutions;
  for (std::size_t i = 0; i < rvecs.size(); ++i) {
    cv::Vec3d rvec(rvecs[i]), tvec(tvecs[i]);
    cv::solvePnPRefineLM(model, image, k, dist, rvec, tvec);
    if (tvec[2] <= 0) continue;  // behind the camera
    const double error = RmsError(model, image, rvec, tvec, k, dist);
    solutions.emplace_back(error, MakeSolution(rvec, tvec, error));
  }
  if (solutions.empty()) return result;
  std::sort(solutions.begin(), solutions.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  result.ok = true;
  result.best = solutions[0].second;
  result.alternative = solutions.size() > 1 ? solutions[1].second : solutions[0].second;
  result.ambiguous =
      solutions.size() > 1 && solutions[1].first < kAmbiguousRatio * solutions[0].first + 0.05;
  return result;
}

}  // namespace pintag::stage
