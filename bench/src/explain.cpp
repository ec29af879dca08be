#include "explain.hpp"

#include <algorithm>
#include <array>

#include "cluster_quads.hpp"
#include "grouping.hpp"
#include "homography.hpp"
#include "pintag/codec/geometry.hpp"
#include "pintag/detector/detector.hpp"
#include "quads.hpp"
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
                        const scene::Camera& camera, const DetectorOptions& tuned) {
  DetectorOptions options = tuned;
  options.intrinsics = CameraIntrinsics{camera.fx, camera.fy, camera.cx, camera.cy, {}};
  options.tag_size_m = kTagSideM;
  const cv::Matx33d to_square = truth.homography.inv();

  // Stage 1: red pixels within the red disk of each element.
  const stage::RedRuns red = stage::FindRedRuns(bgr, {options.red_min_a, options.red_min_b});
  double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
  for (const cv::Point2d& c : truth.corners_px) {
    x0 = std::min(x0, c.x), y0 = std::min(y0, c.y), x1 = std::max(x1, c.x), y1 = std::max(y1, c.y);
  }
  std::array<bool, 4> red_at{};
  for (const stage::RedRun& run : red.runs) {
    if (run.y < y0 || run.y > y1 || run.x1 < x0 || run.x0 > x1) continue;
    for (int x = run.x0; x <= run.x1; ++x) {
      const int e =
          NearestElement(ToSquare(to_square, {double(x), double(run.y)}), geometry::kRedRadius);
      if (e >= 0) red_at[static_cast<std::size_t>(e)] = true;
    }
  }
  const auto red_elements = std::count(red_at.begin(), red_at.end(), true);
  if (red_elements < 3) {
    return "1 red: only " + std::to_string(red_elements) + " of 4 elements have a red pixel";
  }

  // Stage 2: blobs kept by the size and shape limits near each element.
  stage::BlobLimits limits;
  limits.min_area = options.min_element_area_px;
  limits.max_area = std::max<int>(limits.min_area,
                                  static_cast<int>(options.max_element_area_ratio * bgr.total()));
  limits.max_blobs = options.max_blobs;
  std::vector<stage::RedBlob> blobs = stage::FindRedBlobs(red, limits);
  const auto on_elements = [&](const std::vector<stage::RedBlob>& list) {
    std::array<bool, 4> at{};
    std::vector<int> indices;
    for (std::size_t i = 0; i < list.size(); ++i) {
      const int e = NearestElement(ToSquare(to_square, list[i].centroid), kNear);
      if (e < 0) continue;
      at[static_cast<std::size_t>(e)] = true;
      indices.push_back(static_cast<int>(i));
    }
    return std::pair(static_cast<int>(std::count(at.begin(), at.end(), true)), indices);
  };
  if (on_elements(blobs).first < 3) return "2 blobs: < 3 elements give a red blob (size, shape)";

  // Stage 3, as detector.cpp runs it: the ring check, clusters, then quads per cluster.
  std::erase_if(blobs, [&](const stage::RedBlob& b) { return !stage::HasRing(bgr, b); });
  // (Not a structured binding: lambdas below capture on_tag, which C++20 allows and clang 14
  // does not.)
  const std::pair<int, std::vector<int>> ring_kept = on_elements(blobs);
  const std::vector<int>& on_tag = ring_kept.second;
  if (ring_kept.first < 3) return "3a ring check: < 3 element blobs keep their green ring";
  const std::vector<stage::BlobCluster> clusters = stage::ClusterBlobs(blobs, bgr.size());
  const stage::BlobCluster* cluster = nullptr;
  for (const stage::BlobCluster& c : clusters) {
    const auto n = std::count_if(c.blobs.begin(), c.blobs.end(), [&](int b) {
      return std::find(on_tag.begin(), on_tag.end(), b) != on_tag.end();
    });
    if (n >= 3) cluster = &c;
  }
  if (cluster == nullptr) return "3b grouping: no cluster holds >= 3 of the element blobs";
  const cv::Point2d centre_px =
      (truth.corners_px[0] + truth.corners_px[1] + truth.corners_px[2] + truth.corners_px[3]) *
      0.25;
  bool quad_on_tag = false, rough_ok = false;
  // The same outline quads as detector.cpp (not the squares its blobs place when none of these
  // decodes, nor the corner fit: misses there are counted at this stage or at the reason shown).
  const std::vector<stage::Quad> quads = stage::ClusterQuads(
      stage::MinChannel(bgr, cluster->roi), *cluster, blobs, options.min_square_px);
  for (const stage::Quad& q : quads) {
    if (cv::norm((q[0] + q[1] + q[2] + q[3]) * 0.25 - centre_px) >= 0.3 * truth.square_px) continue;
    quad_on_tag = true;
    rough_ok |= stage::AssignElements(stage::HomographyFromQuad(q), blobs, cluster->blobs,
                                      stage::kRoughElementTolerance)
                    .found >= 3;
  }
  if (!quad_on_tag) return "3c quad search: no quad on the tag in its cluster's region";
  if (!rough_ok) return "3d quad found, but < 3 blobs fall on its elements";

  // Later stages: what the detector says about candidates on the tag.
  options.return_rejected = true;
  const DetectResult result = Detector(options).detect(bgr);
  const cv::Point2d centre = centre_px;
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
  return rank > 0 ? reason : "7 no candidate on the tag reached the decoder";
}

}  // namespace pintag::bench
