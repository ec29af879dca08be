// pintag_bench_stages: Google Benchmark micro-benchmarks of each PinTag detector stage on one
// 1080p frame, so that a regression in one stage shows on its own. The frame is rendered once by
// the scene generator (a real photograph, moderate photometry, four PinTags of 160, 80, 48 and
// 32 px at various tilts); the stage inputs are computed once from it, then each stage runs alone.
// Baselines on the same frame: BGR->gray (one pass over the pixels), ArUco and AprilTag.

#include <benchmark/benchmark.h>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "candidates/dark_squares.hpp"
#include "candidates/frame_scan.hpp"
#include "candidates/grouping.hpp"
#include "candidates/quads.hpp"
#include "candidates/red_blobs.hpp"
#include "candidates/redness.hpp"
#include "detectors.hpp"
#include "homography.hpp"
#include "pintag/detector/detector.hpp"
#include "pintag/scene/scene.hpp"
#include "pose/pose.hpp"
#include "reading/model_reader.hpp"
#include "reading/orientation.hpp"
#include "reading/payload.hpp"
#include "reading/sampling.hpp"
#include "sweep.hpp"

namespace pintag::bench {
namespace {

struct Fixture {
  scene::Camera camera;
  scene::Scene tagged;    ///< four PinTags
  scene::Scene tagless;   ///< the same photograph without tags
  scene::Scene aruco;     ///< the same poses with ArUco markers
  scene::Scene apriltag;  ///< … and AprilTags
  DetectorOptions options;
  stage::RedRuns red;
  std::vector<stage::RedBlob> raw_blobs;  ///< before the ring check
  std::vector<stage::RedBlob> blobs;      ///< after it
  std::vector<stage::BlobCluster> clusters;
  std::vector<cv::Mat> dark;  ///< MinChannel per cluster
  struct Candidate {
    int cluster = 0;
    stage::Quad quad;     ///< as found
    stage::Quad refined;  ///< after RefineCorners
    cv::Matx33d h;        ///< from the refined quad
    stage::CellSamples samples;
    stage::OrientationResult orientation;
  };
  std::vector<Candidate> candidates;  ///< quads that decode
  /// The model reader's inputs on the candidates small enough for it (squares up to 170 px): the
  /// model runs only when direct samples do not decode, but these time it on tags whose answer is
  /// known.
  std::vector<reading::Corners> model_corners;
  std::vector<reading::FittedModel> models;
};

/// The fixture's frames are saved as 4:2:0 JPEG (Photometry::Moderate, tuning world).
constexpr ChromaUpsampling kFramesUpsampling = ChromaUpsampling::kBoth;

scene::SceneSpec Spec(Marker marker, bool with_tags) {
  scene::SceneSpec spec;
  spec.seed = 20261122;
  spec.background_photo = 0;
  spec.photometry = scene::Photometry::Moderate(spec.seed);
  if (!with_tags) return spec;
  const struct {
    int side;
    double x, y, tilt, axis, roll;
  } kTags[] = {{160, 400, 300, 0, 0, 10},
               {80, 1300, 280, 40, 30, 200},
               {48, 700, 800, 55, 120, 75},
               {32, 1500, 800, 20, 250, 300}};
  int id = 101;
  for (const auto& t : kTags) {
    scene::PlacedMarker m;
    m.id = id;
    m.texture = marker == Marker::kPinTag  ? scene::PinTagTexture(id * 37)
                : marker == Marker::kAruco ? scene::ArucoTexture(id)
                                           : scene::AprilTagTexture(id);
    if (marker == Marker::kPinTag) m.id = id * 37;
    m.square_side_m = kTagSideM;
    m.pose = scene::MakePose(spec.camera, {t.x, t.y},
                             scene::DistanceForSquarePx(spec.camera, t.side, kTagSideM), t.tilt,
                             t.axis, t.roll);
    spec.markers.push_back(std::move(m));
    ++id;
  }
  return spec;
}

const Fixture& Get() {
  static const Fixture fixture = [] {
    cv::setNumThreads(1);
    Fixture f;
    f.tagged = scene::RenderScene(Spec(Marker::kPinTag, true));
    f.tagless = scene::RenderScene(Spec(Marker::kPinTag, false));
    f.aruco = scene::RenderScene(Spec(Marker::kAruco, true));
    f.apriltag = scene::RenderScene(Spec(Marker::kAprilTag, true));
    f.options.intrinsics = CameraIntrinsics{f.camera.fx, f.camera.fy, f.camera.cx, f.camera.cy, {}};
    f.options.tag_size_m = kTagSideM;
    f.red = stage::FindRedRuns(f.tagged.bgr, {f.options.red_min_a, f.options.red_min_b});
    stage::BlobLimits limits;
    limits.min_area = f.options.min_element_area_px;
    limits.max_area = static_cast<int>(f.options.max_element_area_ratio * f.tagged.bgr.total());
    limits.max_blobs = f.options.max_blobs;
    f.raw_blobs = stage::FindRedBlobs(f.red, limits);
    f.blobs = f.raw_blobs;  // as detector.cpp: blobs without a green ring around them are dropped
    std::erase_if(f.blobs,
                  [&](const stage::RedBlob& b) { return !stage::HasRing(f.tagged.bgr, b); });
    f.clusters = stage::ClusterBlobs(f.blobs, f.tagged.bgr.size());
    const stage::BitThresholds thresholds{f.options.min_bit_span_b, f.options.min_bit_margin};
    for (std::size_t c = 0; c < f.clusters.size(); ++c) {
      f.dark.push_back(stage::MinChannel(f.tagged.bgr, f.clusters[c].roi));
      for (const stage::Quad& q :
           stage::FindQuads(f.dark.back(), f.clusters[c].roi.tl(), f.options.min_square_px)) {
        Fixture::Candidate cand;
        cand.cluster = static_cast<int>(c);
        cand.quad = q;
        cand.refined = q;
        if (!stage::RefineCorners(f.dark.back(), f.clusters[c].roi.tl(), &cand.refined)) continue;
        cand.h = stage::HomographyFromQuad(cand.refined);
        cand.samples = stage::SampleCells(f.tagged.bgr, cand.h);
        cand.orientation = stage::ReadOrientation(cand.samples, thresholds);
        if (!cand.orientation.ok) continue;
        f.candidates.push_back(cand);
        const reading::Corners corners{cand.refined[0], cand.refined[1], cand.refined[2],
                                       cand.refined[3]};
        std::string error;
        reading::FittedModel model =
            reading::FitModel(f.tagged.bgr, kFramesUpsampling, corners, &error);
        if (!model.fit.ok) continue;
        f.model_corners.push_back(corners);
        f.models.push_back(model);  // trivially copyable: a move is a copy
      }
    }
    return f;
  }();
  return fixture;
}

void ReportCounts(benchmark::State& state) {
  const Fixture& f = Get();
  state.counters["raw_blobs"] = static_cast<double>(f.raw_blobs.size());
  state.counters["blobs"] = static_cast<double>(f.blobs.size());
  state.counters["clusters"] = static_cast<double>(f.clusters.size());
  state.counters["tags"] = static_cast<double>(f.candidates.size());
  state.counters["model_fits"] = static_cast<double>(f.models.size());
}

// Google Benchmark's idioms: BM_ names, and `for (auto _ : state)` whose loop variable is unused.
// NOLINTBEGIN(readability-identifier-naming, clang-analyzer-deadcode.DeadStores)

// --- whole frame -------------------------------------------------------------------------------

void BM_Floor_BgrToGray(benchmark::State& state) {
  const Fixture& f = Get();
  cv::Mat gray;
  for (auto _ : state) {
    GrayFloor(f.tagged.bgr, &gray);
    benchmark::DoNotOptimize(gray.data);
  }
}
BENCHMARK(BM_Floor_BgrToGray)->Unit(benchmark::kMillisecond);

void BM_Detect_Full(benchmark::State& state) {
  const Fixture& f = Get();
  const Detector detector(f.options);
  std::size_t found = 0;
  for (auto _ : state) found = detector.detect(f.tagged.bgr).detections.size();
  state.counters["found"] = static_cast<double>(found);
  ReportCounts(state);
}
BENCHMARK(BM_Detect_Full)->Unit(benchmark::kMillisecond);

void BM_Detect_Tagless(benchmark::State& state) {
  const Fixture& f = Get();
  const Detector detector(f.options);
  for (auto _ : state) benchmark::DoNotOptimize(detector.detect(f.tagless.bgr));
}
BENCHMARK(BM_Detect_Tagless)->Unit(benchmark::kMillisecond);

// --- stages, in pipeline order ------------------------------------------------------------------

void BM_Stage1_FindRedRuns(benchmark::State& state) {
  const Fixture& f = Get();
  const stage::RednessThresholds t{f.options.red_min_a, f.options.red_min_b};
  for (auto _ : state) benchmark::DoNotOptimize(stage::FindRedRuns(f.tagged.bgr, t));
  state.counters["runs"] = static_cast<double>(f.red.runs.size());
}
BENCHMARK(BM_Stage1_FindRedRuns)->Unit(benchmark::kMillisecond);

void BM_Stage1_FindRedRuns_Tagless(benchmark::State& state) {
  const Fixture& f = Get();
  const stage::RednessThresholds t{f.options.red_min_a, f.options.red_min_b};
  for (auto _ : state) benchmark::DoNotOptimize(stage::FindRedRuns(f.tagless.bgr, t));
}
BENCHMARK(BM_Stage1_FindRedRuns_Tagless)->Unit(benchmark::kMillisecond);

// The detector's one pass: both redness levels (and, with the argument 1, the half-resolution
// dark image), against two FindRedRuns above. The red tables read 16 entries at a time where the
// CPU has AVX2 (label "gathered"); _OneByOne is the same pass reading one entry per pixel, as on
// CPUs without it.
void TimeScanFrame(benchmark::State& state, stage::RedLookups lookups) {
  const Fixture& f = Get();
  stage::FrameScanRequest request;
  request.red = {f.options.red_min_a, f.options.red_min_b};
  request.faint = stage::RednessThresholds{f.options.faint_red_min_a, f.options.red_min_b};
  request.dark_half = state.range(0) != 0;
  request.lookups = lookups;
  for (auto _ : state) benchmark::DoNotOptimize(stage::ScanFrame(f.tagged.bgr, request));
  const bool gathered = lookups == stage::RedLookups::kFastest && stage::GathersRedLookups();
  state.SetLabel(gathered ? "gathered" : "one by one");
}
void BM_Stage1_ScanFrame(benchmark::State& state) {
  TimeScanFrame(state, stage::RedLookups::kFastest);
}
BENCHMARK(BM_Stage1_ScanFrame)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
void BM_Stage1_ScanFrame_OneByOne(benchmark::State& state) {
  TimeScanFrame(state, stage::RedLookups::kOneByOne);
}
BENCHMARK(BM_Stage1_ScanFrame_OneByOne)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Stage 3e on the whole frame: squares found by their darkness (the frame's tags included, since
// nothing is decoded yet), and on the same photograph without tags.
void DarkSquares(benchmark::State& state, const cv::Mat& bgr) {
  const Fixture& f = Get();
  stage::FrameScanRequest request;
  request.red = {f.options.red_min_a, f.options.red_min_b};
  request.dark_half = true;
  const stage::FrameScan scan = stage::ScanFrame(bgr, request);
  stage::DarkSquareLimits limits;
  limits.min_square_px = f.options.min_square_px;
  std::size_t squares = 0;
  for (auto _ : state) {
    squares = stage::FindDarkSquares(bgr, scan.dark_half, limits, {}).size();
    benchmark::DoNotOptimize(squares);
  }
  state.counters["squares"] = static_cast<double>(squares);
}
void BM_Stage3e_FindDarkSquares(benchmark::State& state) {
  DarkSquares(state, Get().tagged.bgr);
}
BENCHMARK(BM_Stage3e_FindDarkSquares)->Unit(benchmark::kMillisecond);
void BM_Stage3e_FindDarkSquares_Tagless(benchmark::State& state) {
  DarkSquares(state, Get().tagless.bgr);
}
BENCHMARK(BM_Stage3e_FindDarkSquares_Tagless)->Unit(benchmark::kMillisecond);

void BM_Stage2_FindRedBlobs(benchmark::State& state) {
  const Fixture& f = Get();
  stage::BlobLimits limits;
  limits.min_area = f.options.min_element_area_px;
  limits.max_area = static_cast<int>(f.options.max_element_area_ratio * f.tagged.bgr.total());
  limits.max_blobs = f.options.max_blobs;
  for (auto _ : state) benchmark::DoNotOptimize(stage::FindRedBlobs(f.red, limits));
  ReportCounts(state);
}
BENCHMARK(BM_Stage2_FindRedBlobs)->Unit(benchmark::kMicrosecond);

void BM_Stage2_HasRing(benchmark::State& state) {
  const Fixture& f = Get();
  for (auto _ : state) {
    for (const stage::RedBlob& b : f.raw_blobs) {
      benchmark::DoNotOptimize(stage::HasRing(f.tagged.bgr, b));
    }
  }
  ReportCounts(state);
}
BENCHMARK(BM_Stage2_HasRing)->Unit(benchmark::kMicrosecond);

void BM_Stage3_ClusterBlobs(benchmark::State& state) {
  const Fixture& f = Get();
  for (auto _ : state) {
    benchmark::DoNotOptimize(stage::ClusterBlobs(f.blobs, f.tagged.bgr.size()));
  }
  ReportCounts(state);
}
BENCHMARK(BM_Stage3_ClusterBlobs)->Unit(benchmark::kMicrosecond);

void BM_Stage3_MinChannel(benchmark::State& state) {
  const Fixture& f = Get();
  for (auto _ : state) {
    for (const stage::BlobCluster& c : f.clusters) {
      benchmark::DoNotOptimize(stage::MinChannel(f.tagged.bgr, c.roi));
    }
  }
  ReportCounts(state);
}
BENCHMARK(BM_Stage3_MinChannel)->Unit(benchmark::kMicrosecond);

void BM_Stage3_FindQuads(benchmark::State& state) {
  const Fixture& f = Get();
  for (auto _ : state) {
    for (std::size_t c = 0; c < f.clusters.size(); ++c) {
      benchmark::DoNotOptimize(
          stage::FindQuads(f.dark[c], f.clusters[c].roi.tl(), f.options.min_square_px));
    }
  }
  ReportCounts(state);
}
BENCHMARK(BM_Stage3_FindQuads)->Unit(benchmark::kMicrosecond);

void BM_Stage3_AssignElements(benchmark::State& state) {
  const Fixture& f = Get();
  for (auto _ : state) {
    for (const Fixture::Candidate& c : f.candidates) {
      benchmark::DoNotOptimize(stage::AssignElements(
          c.h, f.blobs, f.clusters[static_cast<std::size_t>(c.cluster)].blobs));
    }
  }
  ReportCounts(state);
}
BENCHMARK(BM_Stage3_AssignElements)->Unit(benchmark::kMicrosecond);

void BM_Stage4_RefineCorners(benchmark::State& state) {
  const Fixture& f = Get();
  for (auto _ : state) {
    for (const Fixture::Candidate& c : f.candidates) {
      stage::Quad q = c.quad;
      const auto& cluster = f.clusters[static_cast<std::size_t>(c.cluster)];
      benchmark::DoNotOptimize(
          stage::RefineCorners(f.dark[static_cast<std::size_t>(c.cluster)], cluster.roi.tl(), &q));
    }
  }
  ReportCounts(state);
}
BENCHMARK(BM_Stage4_RefineCorners)->Unit(benchmark::kMicrosecond);

void BM_Stage4_HomographyFromQuad(benchmark::State& state) {
  const Fixture& f = Get();
  for (auto _ : state) {
    for (const Fixture::Candidate& c : f.candidates) {
      benchmark::DoNotOptimize(stage::HomographyFromQuad(c.refined));
    }
  }
  ReportCounts(state);
}
BENCHMARK(BM_Stage4_HomographyFromQuad)->Unit(benchmark::kMicrosecond);

void BM_Stage5_SampleCells(benchmark::State& state) {
  const Fixture& f = Get();
  for (auto _ : state) {
    for (const Fixture::Candidate& c : f.candidates) {
      benchmark::DoNotOptimize(stage::SampleCells(f.tagged.bgr, c.h));
    }
  }
  ReportCounts(state);
}
BENCHMARK(BM_Stage5_SampleCells)->Unit(benchmark::kMicrosecond);

void BM_Stage5b_FitModel(benchmark::State& state) {
  const Fixture& f = Get();
  for (auto _ : state) {
    for (const reading::Corners& corners : f.model_corners) {
      std::string error;
      benchmark::DoNotOptimize(reading::FitModel(f.tagged.bgr, kFramesUpsampling, corners, &error));
    }
  }
  ReportCounts(state);
}
BENCHMARK(BM_Stage5b_FitModel)->Unit(benchmark::kMillisecond);

void BM_Stage5c_DecideCodeword(benchmark::State& state) {
  const Fixture& f = Get();
  for (auto _ : state) {
    for (const reading::FittedModel& model : f.models) {
      benchmark::DoNotOptimize(reading::DecideCodeword(model));
    }
  }
  ReportCounts(state);
}
BENCHMARK(BM_Stage5c_DecideCodeword)->Unit(benchmark::kMillisecond);

void BM_Stage6_ReadOrientation(benchmark::State& state) {
  const Fixture& f = Get();
  const stage::BitThresholds t{f.options.min_bit_span_b, f.options.min_bit_margin};
  for (auto _ : state) {
    for (const Fixture::Candidate& c : f.candidates) {
      benchmark::DoNotOptimize(stage::ReadOrientation(c.samples, t));
    }
  }
  ReportCounts(state);
}
BENCHMARK(BM_Stage6_ReadOrientation)->Unit(benchmark::kMicrosecond);

void BM_Stage6_DecodePayload(benchmark::State& state) {
  const Fixture& f = Get();
  for (auto _ : state) {
    for (const Fixture::Candidate& c : f.candidates) {
      benchmark::DoNotOptimize(stage::DecodePayload(c.orientation.reading));
    }
  }
  ReportCounts(state);
}
BENCHMARK(BM_Stage6_DecodePayload)->Unit(benchmark::kMicrosecond);

void BM_Stage7_EstimatePose(benchmark::State& state) {
  const Fixture& f = Get();
  const CameraIntrinsics& k = *f.options.intrinsics;
  for (auto _ : state) {
    for (const Fixture::Candidate& c : f.candidates) {
      const stage::Quad q = stage::RotateQuad(c.refined, c.orientation.quarter_turns);
      benchmark::DoNotOptimize(stage::EstimatePose(q, k, f.options.tag_size_m));
    }
  }
  ReportCounts(state);
}
BENCHMARK(BM_Stage7_EstimatePose)->Unit(benchmark::kMicrosecond);

// --- the other detectors on the same poses -------------------------------------------------------

void BM_Baseline_Aruco(benchmark::State& state) {
  const Fixture& f = Get();
  auto detector = MakeArucoDetector(f.camera);
  std::size_t found = 0;
  for (auto _ : state) found = detector->detect(f.aruco.bgr).size();
  state.counters["found"] = static_cast<double>(found);
}
BENCHMARK(BM_Baseline_Aruco)->Unit(benchmark::kMillisecond);

void BM_Baseline_AprilTag(benchmark::State& state) {
  const Fixture& f = Get();
  auto detector = MakeAprilTagDetector(f.camera, static_cast<int>(state.range(0)));
  std::size_t found = 0;
  for (auto _ : state) found = detector->detect(f.apriltag.bgr).size();
  state.counters["found"] = static_cast<double>(found);
}
BENCHMARK(BM_Baseline_AprilTag)->Arg(1)->Arg(2)->ArgName("decimate")->Unit(benchmark::kMillisecond);

// --- the test scenes themselves --------------------------------------------------------------

// One 1080p scene of the fixture's four PinTags, a new seed each time: what the tests' and the
// sweep's scenes cost to make (arg 0 moderate, 1 hard photometry).
void BM_Scene_Render(benchmark::State& state) {
  (void)Get();  // photographs loaded and OpenCV held to one thread, as for every stage
  scene::SceneSpec spec = Spec(Marker::kPinTag, true);
  const bool hard = state.range(0) == 1;
  for (auto _ : state) {
    ++spec.seed;
    spec.photometry =
        hard ? scene::Photometry::Hard(spec.seed) : scene::Photometry::Moderate(spec.seed);
    benchmark::DoNotOptimize(scene::RenderScene(spec).bgr.data);
  }
}
BENCHMARK(BM_Scene_Render)->Arg(0)->Arg(1)->ArgName("hard")->Unit(benchmark::kMillisecond);

// NOLINTEND(readability-identifier-naming, clang-analyzer-deadcode.DeadStores)

}  // namespace
}  // namespace pintag::bench

BENCHMARK_MAIN();
