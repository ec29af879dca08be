#include "explain.hpp"

#include <algorithm>
#include <array>
#include <cstdio>

#include "pintag/detector/detector.hpp"
#include "reading/read_tag.hpp"
#include "sweep.hpp"

namespace pintag::bench {
namespace {

cv::Point2d Centre(const std::array<cv::Point2d, 4>& corners) {
  return (corners[0] + corners[1] + corners[2] + corners[3]) * 0.25;
}

/// Mean corner distance between two squares, over the four ways of pairing their corners in order.
double CornerError(const std::array<cv::Point2d, 4>& a, const std::array<cv::Point2d, 4>& b) {
  double best = 1e300;
  for (int turn = 0; turn < 4; ++turn) {
    double sum = 0;
    for (int i = 0; i < 4; ++i)
      sum += cv::norm(a[static_cast<std::size_t>(i)] - b[static_cast<std::size_t>((i + turn) % 4)]);
    best = std::min(best, sum / 4);
  }
  return best;
}

}  // namespace

std::string ExplainMiss(const cv::Mat& bgr, ChromaUpsampling upsampling,
                        const scene::MarkerTruth& truth, const scene::Camera& camera,
                        const DetectorOptions& tuned) {
  DetectorOptions options = tuned;
  options.intrinsics = CameraIntrinsics{camera.fx, camera.fy, camera.cx, camera.cy, {}};
  options.tag_size_m = kTagSideM;
  options.return_rejected = true;

  // The readers on the true corners: what the tag holds for them when the square is exact.
  const stage::BitThresholds thresholds{options.min_bit_span_b, options.min_bit_margin};
  stage::Quad exact;
  for (std::size_t i = 0; i < 4; ++i) exact[i] = truth.corners_px[i];
  const stage::CandidateReading at_truth = stage::ReadCandidate(bgr, upsampling, exact, thresholds);
  const std::string reader =
      !at_truth.reading.payload.key ? "unread at true corners"
      : *at_truth.reading.payload.key == TagKey(static_cast<std::uint16_t>(truth.id))
          ? "read at true corners"
          : "WRONG at true corners";

  // The detector's candidates on the tag: the one nearest the truth decides.
  const DetectResult result = Detector(options).detect(bgr, nullptr, upsampling);
  const cv::Point2d centre = Centre(truth.corners_px);
  double best_error = 1e300;
  std::string best_reason;
  bool decoded = false;
  for (const Detection& d : result.detections) {
    std::array<cv::Point2d, 4> corners;
    for (std::size_t i = 0; i < 4; ++i) corners[i] = {d.corners[i].x, d.corners[i].y};
    if (cv::norm(Centre(corners) - centre) >= 0.3 * truth.square_px) continue;
    const double error = CornerError(corners, truth.corners_px);
    if (error < best_error) {
      best_error = error;
      best_reason = d.key ? "decoded as another key" : d.reject_reason;
      decoded = d.key.has_value();
    }
  }
  if (best_error > 1e299) return "1 no candidate; " + reader;
  char text[256];
  const char* band = best_error < 0.5 ? "< 0.5"
                     : best_error < 1 ? "0.5-1"
                     : best_error < 2 ? "1-2"
                                      : ">= 2";
  std::snprintf(text, sizeof text, "%s candidate, corners %s px off (%s); %s",
                decoded ? "3 wrong" : "2", band,
                best_reason.substr(0, best_reason.find(':')).c_str(), reader.c_str());
  return text;
}

}  // namespace pintag::bench
