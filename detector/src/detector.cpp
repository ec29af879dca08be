// The pipeline of DESIGN.md §3, top to bottom, run twice: at the main redness threshold, then a
// faint pass for small tags it missed. Full-frame work per pass is one table-lookup redness pass
// and one connected-components pass; the rest runs in small regions around red blob clusters.

#include "pintag/detector/detector.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <thread>
#include <vector>

#include "blur_model.hpp"
#include "camera_model.hpp"
#include "cluster_quads.hpp"
#include "corner_fit.hpp"
#include "debug_images.hpp"
#include "duplicates.hpp"
#include "frame_scan.hpp"
#include "grouping.hpp"
#include "homography.hpp"
#include "pintag/codec/geometry.hpp"
#include "pose.hpp"
#include "quads.hpp"
#include "read_tag.hpp"
#include "red_blobs.hpp"
#include "redness.hpp"

namespace pintag {
namespace {

using Clock = std::chrono::steady_clock;

constexpr int kMainMinClusterBlobs = 3;

double Ms(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double, std::milli>(to - from).count();
}

struct ClusterOutput {
  std::vector<Detection> detections;
  std::vector<stage::Quad> quads;  // for the debug image
  double quads_ms = 0;
  double decode_ms = 0;
};

Point2 ToPoint(cv::Point2d p) {
  return {p.x, p.y};
}

double MeanSide(const stage::Quad& quad) {
  double perimeter = 0;
  for (int i = 0; i < 4; ++i) perimeter += cv::norm(quad[(i + 1) % 4] - quad[i]);
  return perimeter / 4;
}

// A decoded candidate as a Detection (corners turned so that C0 comes first).
Detection MakeDetection(stage::Quad quad, const stage::TagReading& reading,
                        const std::array<bool, 4>& blob_at_sampled_element) {
  Detection d;
  const stage::OrientationResult& o = reading.orientation;
  const int r = o.quarter_turns;
  quad = stage::RotateQuad(quad, r);
  const cv::Matx33d h = stage::HomographyFromQuad(quad);
  d.key = reading.payload.key;
  for (int i = 0; i < 4; ++i) {
    d.corners[i] = ToPoint(quad[i]);
    const geometry::Point c = geometry::kElementCentres[i];
    d.element_centres[i] = ToPoint(stage::Apply(h, c.x, c.y));
    d.element_seen[i] = blob_at_sampled_element[(i + r) % 4];
  }
  for (int i = 0; i < 9; ++i) d.homography[i] = h.val[i];
  d.square_px = MeanSide(quad);
  d.cells = o.reading;
  d.margins = o.margins;
  d.unknown_bits = o.unknown;
  d.min_known_margin = o.min_known_margin;
  d.bits_from_second_copy = reading.payload.bits_from_second_copy;
  d.bit_from_parity = reading.payload.bit_from_parity;
  d.read_through_blur_model = reading.throughBlurModel();
  return d;
}

// One quad of a cluster through stages 4 to 6; true when it decoded.
bool ProcessQuad(const cv::Mat& bgr, const cv::Mat& dark, const std::vector<stage::RedBlob>& blobs,
                 const stage::BlobCluster& cluster, stage::Quad quad,
                 const DetectorOptions& options, ClusterOutput* out) {
  auto t1 = Clock::now();
  const stage::ElementAssignment rough = stage::AssignElements(
      stage::HomographyFromQuad(quad), blobs, cluster.blobs, stage::kRoughElementTolerance);
  if (rough.found < cluster.min_elements) return false;
  const bool refined = stage::RefineCorners(dark, cluster.roi.tl(), &quad);
  const cv::Matx33d h = stage::HomographyFromQuad(quad);
  stage::ElementAssignment assignment = stage::AssignElements(h, blobs, cluster.blobs);
  const auto t2 = Clock::now();
  out->quads_ms += Ms(t1, t2);
  const auto reject = [&](std::string reason, const stage::OrientationResult* o = nullptr) {
    if (!options.return_rejected) return false;
    Detection d;
    d.reject_reason = std::move(reason);
    for (int i = 0; i < 4; ++i) d.corners[i] = ToPoint(quad[i]);
    d.square_px = MeanSide(quad);
    if (o != nullptr) {
      d.cells = o->reading;
      d.margins = o->margins;
      d.unknown_bits = o->unknown;
    }
    out->detections.push_back(d);
    return false;
  };
  if (!refined) return reject("square edges not found");
  if (assignment.found < cluster.min_elements || assignment.conflict) {
    return reject("red blobs do not match the elements");
  }
  const stage::BitThresholds thresholds{options.min_bit_span_b, options.min_bit_margin};
  stage::TagReading reading = stage::ReadTag(bgr, h, thresholds);
  if (!reading.payload.key && reading.fit.ok) {
    // No reader decoded it: the corners may be off by more than small cells allow.
    const stage::CornerFit fitted = stage::FitCornersThroughBlur(bgr, quad, reading.fit);
    if (fitted.moved) {
      const cv::Matx33d moved = stage::HomographyFromQuad(fitted.quad);
      stage::TagReading again =
          stage::ReadTag(bgr, moved, thresholds, stage::kFittedCornersNearestCodewordMinLead);
      // The moved square must pass step 4's element check too.
      const stage::ElementAssignment moved_assignment =
          stage::AssignElements(moved, blobs, cluster.blobs);
      if (again.payload.key && moved_assignment.found >= cluster.min_elements &&
          !moved_assignment.conflict) {
        quad = fitted.quad;
        reading = std::move(again);
        assignment = moved_assignment;
      }
    }
  }
  out->decode_ms += Ms(t2, Clock::now());
  if (!reading.orientation.ok) return reject(reading.orientation.error);
  if (!reading.payload.key) return reject(reading.payload.error, &reading.orientation);
  std::array<bool, 4> seen{};
  for (int e = 0; e < 4; ++e) seen[e] = assignment.blob[e] >= 0;
  out->detections.push_back(MakeDetection(quad, reading, seen));
  return true;
}

void ProcessCluster(const cv::Mat& bgr, const std::vector<stage::RedBlob>& blobs,
                    const stage::BlobCluster& cluster, const DetectorOptions& options,
                    ClusterOutput* out) {
  const auto t0 = Clock::now();
  const cv::Mat dark = stage::MinChannel(bgr, cluster.roi);
  const std::vector<stage::Quad> quads =
      stage::ClusterQuads(dark, cluster, blobs, options.min_square_px);
  out->quads.insert(out->quads.end(), quads.begin(), quads.end());
  out->quads_ms += Ms(t0, Clock::now());

  bool decoded = false;
  for (const stage::Quad& quad : quads) {
    decoded = ProcessQuad(bgr, dark, blobs, cluster, quad, options, out) || decoded;
  }
  if (decoded) return;
  // The outline gave no tag (a dim quiet zone on dark ground merges with the ground, or leaves
  // only a shrunken outline): the blobs place the square, and step 4 looks for its edges there.
  const std::vector<stage::Quad> placed =
      stage::ClusterElementQuads(cluster, blobs, options.min_square_px);
  out->quads.insert(out->quads.end(), placed.begin(), placed.end());
  for (const stage::Quad& quad : placed) {
    if (ProcessQuad(bgr, dark, blobs, cluster, quad, options, out)) break;
  }
}

bool InsideDecodedTag(cv::Point2d p, const std::vector<Detection>& detections, std::size_t count) {
  for (std::size_t i = 0; i < count; ++i) {
    const Detection& d = detections[i];
    if (!d.key) continue;
    std::vector<cv::Point2f> square;
    for (const Point2& c : d.corners)
      square.emplace_back(static_cast<float>(c.x), static_cast<float>(c.y));
    if (cv::pointPolygonTest(square, cv::Point2f(p), false) >= 0) return true;
  }
  return false;
}

// Stages 2 to 6 on the red runs of one redness threshold: every candidate's detection (decoded, or
// rejected when asked for) is appended to `result`, and the stage times are added to its timings.
void RunRedPass(const cv::Mat& bgr, const stage::RedRuns& red, int max_element_area_px,
                int min_cluster_blobs, const DetectorOptions& options,
                const stage::DebugImages* debug, DetectResult* result,
                std::vector<stage::Quad>* all_quads) {
  const auto t_red = Clock::now();
  if (debug != nullptr && debug->enabled()) debug->redness(stage::RunsToMask(red));

  stage::BlobLimits limits;
  limits.min_area = options.min_element_area_px;
  limits.max_area = std::max<int>(limits.min_area, max_element_area_px);
  limits.max_blobs = options.max_blobs;
  std::vector<stage::RedBlob> blobs = stage::FindRedBlobs(red, limits);
  // A later pass looks only for tags the earlier ones did not decode: the blobs inside a decoded
  // square are its elements again.
  const std::size_t decoded_before = result->detections.size();
  std::erase_if(blobs, [&](const stage::RedBlob& b) {
    return InsideDecodedTag(b.centroid, result->detections, decoded_before) ||
           !stage::HasRing(bgr, b);
  });
  const std::vector<stage::BlobCluster> clusters =
      stage::ClusterBlobs(blobs, bgr.size(), min_cluster_blobs);
  const auto t_blobs = Clock::now();
  result->timings.blobs_ms += Ms(t_red, t_blobs);
  if (debug != nullptr) debug->blobs(bgr, blobs, clusters);

  std::vector<ClusterOutput> outputs(clusters.size());
  const int threads = std::clamp(options.threads, 1, 64);
  if (threads == 1 || clusters.size() < 2) {
    for (std::size_t i = 0; i < clusters.size(); ++i) {
      ProcessCluster(bgr, blobs, clusters[i], options, &outputs[i]);
    }
  } else {
    std::atomic<std::size_t> next{0};
    std::vector<std::thread> pool;
    pool.reserve(static_cast<std::size_t>(threads));
    for (int t = 0; t < threads; ++t) {
      pool.emplace_back([&] {
        for (std::size_t i; (i = next++) < clusters.size();) {
          ProcessCluster(bgr, blobs, clusters[i], options, &outputs[i]);
        }
      });
    }
    for (std::thread& t : pool) t.join();
  }
  for (ClusterOutput& o : outputs) {
    result->timings.quads_ms += o.quads_ms;
    result->timings.decode_ms += o.decode_ms;
    for (Detection& d : o.detections) result->detections.push_back(std::move(d));
    all_quads->insert(all_quads->end(), o.quads.begin(), o.quads.end());
  }
}

}  // namespace

std::string_view ToString(IntrinsicsSource source) {
  switch (source) {
    case IntrinsicsSource::kGiven:
      return "given";
    case IntrinsicsSource::kExif:
      return "exif";
    case IntrinsicsSource::kAssumed:
      return "assumed";
  }
  return "assumed";
}

Detector::Detector(DetectorOptions options) : options_(std::move(options)) {}

DetectResult Detector::detect(const LoadedImage& image) const {
  return detect(image.bgr, &image.exif);
}

DetectResult Detector::detect(const cv::Mat& bgr, const ExifCamera* exif) const {
  DetectResult result;
  if (bgr.empty()) {
    result.error = "empty image";
    return result;
  }
  if (bgr.type() != CV_8UC3) {
    result.error = "image must be 8-bit BGR (CV_8UC3)";
    return result;
  }
  const auto start = Clock::now();
  const stage::ResolvedCamera camera = stage::ResolveCamera(options_, exif, bgr.cols, bgr.rows);
  result.intrinsics = camera.intrinsics;
  result.intrinsics_source = camera.source;
  const stage::DebugImages debug(options_.debug_dir);

  stage::FrameScanRequest scan_request;
  scan_request.red = {options_.red_min_a, options_.red_min_b};
  const bool faint_pass = options_.faint_red_min_a < options_.red_min_a;
  if (faint_pass) scan_request.faint = {options_.faint_red_min_a, options_.red_min_b};
  const stage::FrameScan scan = stage::ScanFrame(bgr, scan_request);
  result.timings.redness_ms += Ms(start, Clock::now());

  std::vector<stage::Quad> all_quads;
  RunRedPass(bgr, scan.red, static_cast<int>(options_.max_element_area_ratio * bgr.total()),
             kMainMinClusterBlobs, options_, &debug, &result, &all_quads);
  if (faint_pass) {
    RunRedPass(bgr, scan.faint, options_.faint_max_element_area_px,
               std::max(2, options_.faint_min_blobs), options_, nullptr, &result, &all_quads);
  }
  debug.quads(bgr, all_quads);
  stage::RemoveDuplicates(&result.detections);

  const auto t_pose = Clock::now();
  for (Detection& d : result.detections) {
    d.intrinsics_source = camera.source;
    if (!d.key) continue;
    std::array<cv::Point2d, 4> corners;
    for (int i = 0; i < 4; ++i) corners[i] = {d.corners[i].x, d.corners[i].y};
    const stage::PoseResult pose =
        stage::EstimatePose(corners, camera.intrinsics, options_.tag_size_m);
    if (!pose.ok) continue;
    d.pose = pose.best;
    d.alternative_pose = pose.alternative;
    d.pose_ambiguous = pose.ambiguous;
  }
  const auto end = Clock::now();
  result.timings.pose_ms = Ms(t_pose, end);
  result.timings.total_ms = Ms(start, end);
  debug.detections(bgr, result.detections);
  return result;
}

}  // namespace pintag
