// The pipeline of DESIGN.md §3, top to bottom: one pass over the frame (both redness levels, and
// min(R, G, B) at full and half resolution), stages 2-6 at the main redness threshold, again at the
// faint one for small tags the first missed, then candidates found by their dark square alone
// outside the tags decoded so far. Whole-frame work is that one pass, a connected-components pass
// per level and one contour pass at half resolution; the rest runs in small regions around
// candidates.

#include "pintag/detector/detector.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <functional>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <thread>
#include <vector>

#include "candidates/cluster_quads.hpp"
#include "candidates/dark_squares.hpp"
#include "candidates/frame_scan.hpp"
#include "candidates/grouping.hpp"
#include "candidates/quads.hpp"
#include "candidates/red_blobs.hpp"
#include "candidates/redness.hpp"
#include "colour_content.hpp"
#include "debug_images.hpp"
#include "duplicates.hpp"
#include "elapsed_ms.hpp"
#include "homography.hpp"
#include "pintag/codec/geometry.hpp"
#include "pose/camera_model.hpp"
#include "pose/pose.hpp"
#include "reading/read_tag.hpp"

namespace pintag {
namespace {

using Clock = std::chrono::steady_clock;

constexpr int kMainMinClusterBlobs = 3;
// A refined square this close to one the readers have tried is that square again (another
// outline of it, or a later pass finding the same cluster): reading it again gives the same
// answer, and a model read costs milliseconds. (Load frames: 4 of 23 model reads were repeats.)
constexpr double kSameSquarePx = 0.25;

// The squares a detect() call looked at.
struct Candidates {
  std::vector<stage::Quad> found;  ///< every quad (for the debug image)
  std::vector<stage::Quad> read;   ///< those the readers tried, as they were read
};

struct ClusterOutput {
  std::vector<Detection> detections;
  Candidates candidates;
  double quads_ms = 0;
  stage::ReadingTimes reading;  ///< summed over the candidates; model_read counted in model_reads
  int model_reads = 0;
  int model_rereads = 0;
  int mosaic_rereads = 0;
  int model_skipped = 0;

  void add(const stage::ReadingTimes& t) {
    reading.sample_ms += t.sample_ms;
    reading.model_fit_ms += t.model_fit_ms;
    reading.codeword_ms += t.codeword_ms;
    model_reads += t.model_read ? 1 : 0;
    model_rereads += t.model_rereads;
    mosaic_rereads += t.mosaic_rereads;
    model_skipped += t.model_skipped ? 1 : 0;
  }
};

Point2 ToPoint(cv::Point2d p) {
  return {p.x, p.y};
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
  d.square_px = stage::MeanSidePx(quad);
  d.cells = o.reading;
  d.margins = o.margins;
  d.unknown_bits = o.unknown;
  d.min_known_margin = o.min_known_margin;
  d.bits_from_second_copy = reading.payload.bits_from_second_copy;
  d.bit_from_parity = reading.payload.bit_from_parity;
  d.read_through_blur_model = reading.throughModel();
  return d;
}

// A candidate no reader decoded, for DetectorOptions::return_rejected.
Detection Rejected(const stage::Quad& quad, std::string reason,
                   const stage::OrientationResult* orientation) {
  Detection d;
  d.reject_reason = std::move(reason);
  for (int i = 0; i < 4; ++i) d.corners[i] = ToPoint(quad[i]);
  d.square_px = stage::MeanSidePx(quad);
  if (orientation != nullptr) {
    d.cells = orientation->reading;
    d.margins = orientation->margins;
    d.unknown_bits = orientation->unknown;
  }
  return d;
}

// One quad of a cluster through stages 4 to 6; true when it decoded.
bool ProcessQuad(const cv::Mat& bgr, ChromaUpsampling upsampling, const cv::Mat& dark,
                 const std::vector<stage::RedBlob>& blobs, const stage::BlobCluster& cluster,
                 stage::Quad quad, const std::vector<stage::Quad>& read_before,
                 const DetectorOptions& options, stage::ModelBudget* budget, ClusterOutput* out) {
  auto t1 = Clock::now();
  const stage::ElementAssignment rough = stage::AssignElements(
      stage::HomographyFromQuad(quad), blobs, cluster.blobs, stage::kRoughElementTolerance);
  if (rough.found < cluster.min_elements) return false;
  const bool refined = stage::RefineCorners(dark, cluster.roi.tl(), &quad);
  const cv::Matx33d h = stage::HomographyFromQuad(quad);
  stage::ElementAssignment assignment = stage::AssignElements(h, blobs, cluster.blobs);
  const auto t2 = Clock::now();
  out->quads_ms += ElapsedMs(t1, t2);
  const auto reject = [&](std::string reason, const stage::OrientationResult* o = nullptr) {
    if (options.return_rejected) out->detections.push_back(Rejected(quad, std::move(reason), o));
    return false;
  };
  if (!refined) return reject("square edges not found");
  if (assignment.found < cluster.min_elements || assignment.conflict) {
    return reject("red blobs do not match the elements");
  }
  const auto read_already = [&](const stage::Quad& q) {
    return stage::SameSquare(q, quad, kSameSquarePx);
  };
  if (std::any_of(read_before.begin(), read_before.end(), read_already) ||
      std::any_of(out->candidates.read.begin(), out->candidates.read.end(), read_already)) {
    return false;  // its rejection, if asked for, was reported the first time
  }
  const stage::BitThresholds thresholds{options.min_bit_span_b, options.min_bit_margin};
  out->candidates.read.push_back(quad);
  // A square moved by the corner fit must pass step 4's element check too.
  stage::ElementAssignment fitted_assignment;
  const stage::CandidateReading candidate = stage::ReadCandidate(
      bgr, upsampling, quad, thresholds,
      [&](const stage::Quad& fitted) {
        fitted_assignment =
            stage::AssignElements(stage::HomographyFromQuad(fitted), blobs, cluster.blobs);
        return fitted_assignment.found >= cluster.min_elements && !fitted_assignment.conflict;
      },
      budget);
  const stage::TagReading& reading = candidate.reading;
  if (candidate.corners_fitted) {
    quad = candidate.quad;
    assignment = fitted_assignment;
  }
  out->add(candidate.times);
  if (!reading.payload.key) {
    // The last reader's word: the model's when it was tried, else the direct samples'.
    if (!reading.orientation.ok) {
      return reject(reading.payload.error.empty() ? reading.orientation.error
                                                  : reading.payload.error);
    }
    return reject(reading.payload.error, &reading.orientation);
  }
  std::array<bool, 4> seen{};
  for (int e = 0; e < 4; ++e) seen[e] = assignment.blob[e] >= 0;
  out->detections.push_back(MakeDetection(quad, reading, seen));
  return true;
}

void ProcessCluster(const cv::Mat& bgr, ChromaUpsampling upsampling, const cv::Mat& min_channel,
                    const std::vector<stage::RedBlob>& blobs, const stage::BlobCluster& cluster,
                    const std::vector<stage::Quad>& read_before, const DetectorOptions& options,
                    stage::ModelBudget* budget, ClusterOutput* out) {
  const auto t0 = Clock::now();
  const cv::Mat dark = min_channel(cluster.roi);
  const std::vector<stage::Quad> quads =
      stage::ClusterQuads(dark, cluster, blobs, options.min_square_px);
  out->candidates.found.insert(out->candidates.found.end(), quads.begin(), quads.end());
  out->quads_ms += ElapsedMs(t0, Clock::now());

  bool decoded = false;
  for (const stage::Quad& quad : quads) {
    decoded = ProcessQuad(bgr, upsampling, dark, blobs, cluster, quad, read_before, options, budget,
                          out) ||
              decoded;
  }
  if (decoded) return;
  // The outline gave no tag (a dim quiet zone on dark ground merges with the ground, or leaves
  // only a shrunken outline): the blobs place the square, and step 4 looks for its edges there.
  const std::vector<stage::Quad> placed =
      stage::ClusterElementQuads(cluster, blobs, options.min_square_px);
  out->candidates.found.insert(out->candidates.found.end(), placed.begin(), placed.end());
  for (const stage::Quad& quad : placed) {
    if (ProcessQuad(bgr, upsampling, dark, blobs, cluster, quad, read_before, options, budget,
                    out)) {
      break;
    }
  }
}

// A square found by its darkness alone (stage 3e) through stages 4 to 6. Its corners are refined
// already; there are no red blobs to hold against its elements, so the readers' rules decide.
void ProcessDarkSquare(const cv::Mat& bgr, ChromaUpsampling upsampling, const stage::Quad& quad,
                       const DetectorOptions& options, stage::ModelBudget* budget,
                       ClusterOutput* out) {
  const stage::BitThresholds thresholds{options.min_bit_span_b, options.min_bit_margin};
  const stage::CandidateReading candidate = stage::ReadCandidate(
      bgr, upsampling, quad, thresholds,
      [&](const stage::Quad& fitted) { return stage::ElementsOutshineCentre(bgr, fitted); },
      budget);
  out->add(candidate.times);
  const stage::TagReading& reading = candidate.reading;
  if (reading.payload.key) {
    out->detections.push_back(MakeDetection(candidate.quad, reading, {}));
  } else if (options.return_rejected) {
    const bool oriented = reading.orientation.ok;
    out->detections.push_back(
        Rejected(candidate.quad,
                 reading.payload.error.empty() ? reading.orientation.error : reading.payload.error,
                 oriented ? &reading.orientation : nullptr));
  }
}

// Runs work(i) for i in [0, count) on up to `threads` threads (the caller's alone for 1).
void ForEach(std::size_t count, int threads, const std::function<void(std::size_t)>& work) {
  threads = std::clamp(threads, 1, 64);
  if (threads == 1 || count < 2) {
    for (std::size_t i = 0; i < count; ++i) work(i);
    return;
  }
  std::atomic<std::size_t> next{0};
  std::vector<std::thread> pool;
  pool.reserve(static_cast<std::size_t>(threads));
  for (int t = 0; t < threads; ++t) {
    pool.emplace_back([&] {
      for (std::size_t i; (i = next++) < count;) work(i);
    });
  }
  for (std::thread& t : pool) t.join();
}

// Adds what each candidate's work gave to the result.
void Collect(std::vector<ClusterOutput>& outputs, DetectResult* result, Candidates* candidates) {
  for (ClusterOutput& o : outputs) {
    StageTimings& t = result->timings;
    t.quads_ms += o.quads_ms;
    t.sample_ms += o.reading.sample_ms;
    t.model_fit_ms += o.reading.model_fit_ms;
    t.codeword_ms += o.reading.codeword_ms;
    t.model_reads += o.model_reads;
    t.model_rereads += o.model_rereads;
    t.mosaic_rereads += o.mosaic_rereads;
    t.model_skipped += o.model_skipped;
    for (Detection& d : o.detections) result->detections.push_back(std::move(d));
    candidates->found.insert(candidates->found.end(), o.candidates.found.begin(),
                             o.candidates.found.end());
    candidates->read.insert(candidates->read.end(), o.candidates.read.begin(),
                            o.candidates.read.end());
  }
}

bool InsideDecodedTag(cv::Point2d p, const std::vector<Detection>& detections, std::size_t count) {
  for (std::size_t i = 0; i < count; ++i) {
    const Detection& d = detections[i];
    if (!d.key) continue;
    stage::Quad square;
    for (std::size_t c = 0; c < 4; ++c) square[c] = {d.corners[c].x, d.corners[c].y};
    if (stage::QuadContains(square, p)) return true;
  }
  return false;
}

// Stages 2 to 6 on the red runs of one redness threshold: every candidate's detection (decoded, or
// rejected when asked for) is appended to `result`, and the stage times are added to its timings.
void RunRedPass(const cv::Mat& bgr, ChromaUpsampling upsampling, const cv::Mat& min_channel,
                const stage::RedRuns& red, int max_element_area_px, int min_cluster_blobs,
                int max_cluster_blobs, const DetectorOptions& options,
                const stage::DebugImages* debug, stage::ModelBudget* budget, DetectResult* result,
                Candidates* candidates) {
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
  std::vector<stage::BlobCluster> clusters =
      stage::ClusterBlobs(blobs, bgr.size(), min_cluster_blobs, max_cluster_blobs);
  // The model reads go first to the clusters most like a tag: those with the most blobs.
  std::stable_sort(clusters.begin(), clusters.end(),
                   [](const stage::BlobCluster& a, const stage::BlobCluster& b) {
                     return a.blobs.size() > b.blobs.size();
                   });
  const auto t_blobs = Clock::now();
  result->timings.blobs_ms += ElapsedMs(t_red, t_blobs);
  if (debug != nullptr) debug->blobs(bgr, blobs, clusters);

  std::vector<ClusterOutput> outputs(clusters.size());
  ForEach(clusters.size(), options.threads, [&](std::size_t i) {
    // Squares of earlier passes only: within a pass, clusters may run in parallel.
    ProcessCluster(bgr, upsampling, min_channel, blobs, clusters[i], candidates->read, options,
                   budget, &outputs[i]);
  });
  Collect(outputs, result, candidates);
}

// Stage 3e and stages 4 to 6 for squares found by their darkness, outside the tags decoded so far
// and the squares the readers have tried already: a tag the red passes placed and could not read
// is not read again. Reading it again from the dark square's corners found 3 more of 1,309 tags
// over seeds 1-3 and doubled the time of those frames (seconds on hard-light 32 px tags).
void RunDarkSquarePass(const cv::Mat& bgr, ChromaUpsampling upsampling, const cv::Mat& dark_half,
                       const DetectorOptions& options, stage::ModelBudget* budget,
                       DetectResult* result, Candidates* candidates) {
  const auto start = Clock::now();
  const std::size_t decoded_before = result->detections.size();
  stage::DarkSquareLimits limits;
  limits.min_square_px = options.min_square_px;
  const std::vector<stage::Quad> squares =
      stage::FindDarkSquares(bgr, dark_half, limits, [&](cv::Point2d centre) {
        return InsideDecodedTag(centre, result->detections, decoded_before) ||
               std::any_of(candidates->read.begin(), candidates->read.end(),
                           [&](const stage::Quad& q) { return stage::QuadContains(q, centre); });
      });
  result->timings.quads_ms += ElapsedMs(start, Clock::now());
  std::vector<ClusterOutput> outputs(squares.size());
  ForEach(squares.size(), options.threads, [&](std::size_t i) {
    outputs[i].candidates.found.push_back(squares[i]);
    ProcessDarkSquare(bgr, upsampling, squares[i], options, budget, &outputs[i]);
  });
  Collect(outputs, result, candidates);
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
  return detect(image.bgr, &image.exif, image.chroma_upsampling);
}

DetectResult Detector::detect(const cv::Mat& bgr, const ExifCamera* exif) const {
  return detect(bgr, exif, ChromaUpsampling::kBoth);
}

DetectResult Detector::detect(const cv::Mat& bgr, const ExifCamera* exif,
                              ChromaUpsampling upsampling) const {
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
  scan_request.min_channel = true;
  scan_request.dark_half = options_.dark_square_candidates;
  const stage::FrameScan scan = stage::ScanFrame(bgr, scan_request);
  result.timings.redness_ms += ElapsedMs(start, Clock::now());

  Candidates candidates;
  stage::ModelBudget budget(std::max(0, options_.max_model_reads));
  RunRedPass(bgr, upsampling, scan.min_channel, scan.red,
             static_cast<int>(options_.max_element_area_ratio * bgr.total()), kMainMinClusterBlobs,
             /*max_cluster_blobs=*/0, options_, &debug, &budget, &result, &candidates);
  if (faint_pass) {
    RunRedPass(bgr, upsampling, scan.min_channel, scan.faint, options_.faint_max_element_area_px,
               std::max(2, options_.faint_min_blobs), std::max(0, options_.faint_max_cluster_blobs),
               options_, nullptr, &budget, &result, &candidates);
  }
  if (options_.dark_square_candidates) {
    RunDarkSquarePass(bgr, upsampling, scan.dark_half, options_, &budget, &result, &candidates);
  }
  debug.quads(bgr, candidates.found);
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
  result.timings.pose_ms = ElapsedMs(t_pose, Clock::now());
  const bool read_any = std::any_of(result.detections.begin(), result.detections.end(),
                                    [](const Detection& d) { return d.key.has_value(); });
  if (!read_any && !stage::HoldsColour(bgr)) {
    result.warnings.push_back(
        {"no_colour",
         "the photo has no colour; PinTag reads its tags from red and green, so take the photo "
         "in colour (not a black-and-white or document mode)"});
  }
  const auto end = Clock::now();
  result.timings.total_ms = ElapsedMs(start, end);
  debug.detections(bgr, result.detections);
  if (std::string failure = debug.failure(); !failure.empty()) result.error = std::move(failure);
  return result;
}

}  // namespace pintag
