#include "explain.hpp"

#include <algorithm>
#include <array>

#include "pintag/codec/geometry.hpp"
#include "pintag/detector/detector.hpp"
#include "red_blobs.hpp"
#include "redness.hpp"
#include "sweep.hpp"

namespace pintag::bench {
namespace {

constexpr double kNear =
    0.08;  ///< square units: a blob this near an element centre is that element

cv::Point2d ToSquare(const cv::Matx33d& image_to_square, cv::Point2d p) {
  const cv::Vec3d q = image_to_square * cv::Vec3d(p.x, p.y, 1);
  return {q[0] / q[2], q[1] / q[2]};
}

int NearestElement(cv::Point2d square_point, double radius) {
  for (int e = 0; e < 4; ++e) {
    const geometry::Point c = geometry::kElementCentres[e];
    if (cv::norm(square_point - cv::Point2d(c.x, c.y)) <= radius) return e;
  }
  return -1;
}

}  // namespace

std::string ExplainMiss(const cv::Mat& bgr, const scene::MarkerTruth& truth,
                        const scene::Camera& camera) {
  DetectorOptions options;
  options.intrinsics = CameraIntrinsics{camera.fx, camera.fy, camera.cx, camera.cy, {}};
  options.tag_size_m = kTagSideM;
  const cv::Matx33d to_square = truth.homography.inv();

  // Stage 1: red pixels within the red disk of each element.
  const stage::RedRuns red = stage::FindRedRuns(bgr, {options.red_min_a, options.red_min_b});
  cv::Rect2d box(truth.corners_px[0], truth.corners_px[0]);
  for (const cv::Point2d& c : truth.corners_px) box |= cv::Rect2d(c, c);
  std::array<bool, 4> red_at{};
  for (const stage::RedRun& run : red.runs) {
    if (run.y < box.y || run.y > box.y + box.height || run.x1 < box.x || run.x0 > box.x + box.width)
      continue;
    for (int x = run.x0; x <= run.x1; ++x) {
      const int e =
          NearestElement(ToSquare(to_square, {double(x), double(run.y)}), geometry::kRedRadius);
      if (e >= 0) red_at[static_cast<std::size_t>(e)] = true;
    }
  }
  if (std::count(red_at.begin(), red_at.end(), true) < 3)
    return "1 red: < 3 elements have a red pixel";

  // Stage 2: blobs kept by the size and shape limits near each element.
  stage::BlobLimits limits;
  limits.min_area = options.min_element_area_px;
  limits.max_area = std::max<int>(limits.min_area,
                                  static_cast<int>(options.max_element_area_ratio * bgr.total()));
  limits.max_blobs = options.max_blobs;
  std::array<bool, 4> blob_at{};
  for (const stage::RedBlob& b : stage::FindRedBlobs(red, limits)) {
    const int e = NearestElement(ToSquare(to_square, b.centroid), kNear);
    if (e >= 0) blob_at[static_cast<std::size_t>(e)] = true;
  }
  if (std::count(blob_at.begin(), blob_at.end(), true) < 3)
    return "2 blobs: < 3 elements give a red blob (size, shape)";

  // Later stages: what the detector says about candidates on the tag.
  options.return_rejected = true;
  const DetectResult result = Detector(options).detect(bgr);
  const cv::Point2d centre =
      (truth.corners_px[0] + truth.corners_px[1] + truth.corners_px[2] + truth.corners_px[3]) *
      0.25;
  // The most advanced stage any candidate on the tag reached decides.
  std::string reason;
  int rank = 0;
  for (const Detection& d : result.detections) {
    cv::Point2d c;
    for (const Point2& p : d.corners) c += cv::Point2d(p.x, p.y) * 0.25;
    if (cv::norm(c - centre) >= 0.3 * truth.square_px) continue;
    if (d.key) return "8 decoded, but another key or off the tag";
    const std::string& why = d.reject_reason;
    const int r = why == "square edges not found"                ? 1
                  : why == "red blobs do not match the elements" ? 2
                  : why.find("orientation") != std::string::npos ? 3
                                                                 : 4;
    if (r > rank) {
      rank = r;
      reason = (r == 1 || r == 2 ? "4 " : r == 3 ? "5 " : "6 ") + why;
    }
  }
  return rank > 0 ? reason : "3 no candidate square (ring check, grouping or quad search)";
}

}  // namespace pintag::bench
