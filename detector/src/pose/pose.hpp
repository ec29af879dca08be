#pragma once
// Stage 7, pose: both planar solutions (IPPE) from the square's four sub-pixel corners, each
// refined by Levenberg–Marquardt; the one with the lower reprojection error is the pose, the other
// is reported too, and the pair is flagged ambiguous when their errors are close.

#include <array>
#include <opencv2/core.hpp>

#include "pintag/detector/detection.hpp"

namespace pintag::stage {

struct PoseResult {
  bool ok = false;
  PoseSolution best;
  PoseSolution alternative;
  bool ambiguous = false;
};

/// `corners` C0 … C3 in px; model: square of side `tag_size_m` centred at the origin, C0 at
/// (−s/2, −s/2, 0), x towards C1, y towards C3.
PoseResult EstimatePose(const std::array<cv::Point2d, 4>& corners, const CameraIntrinsics& camera,
                        double tag_size_m);

/// Fills rotation (matrix, vector, quaternion), translation and distance from rvec / tvec.
PoseSolution MakeSolution(const cv::Vec3d& rvec, const cv::Vec3d& tvec, double error_px);

}  // namespace pintag::stage
