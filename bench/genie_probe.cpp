// pintag_genie_probe: how many small tags any reader could read. For each tagged frame of the
// sweep (tags up to --max-size px) it asks an ideal reader — one told the pose, the print, the
// light, the optics and the phone's processing, everything but the key — which key the photo
// holds. That reader renders the frame without sensor noise and without the JPEG (whose
// quantisation no reader knows beforehand, so it meets it as noise), once for the true key and
// once for every key that differs from it in one or two of the 15 data bits (the codewords
// nearest the truth), and picks the rendering nearest the photo in the colour samples the JPEG kept
// (luma per pixel, Cb and Cr per 2 x 2 block), each channel in units of its own noise. Where even
// it cannot tell the truth from a neighbour, the photo does not hold the key; where it can and
// PinTag does not, the loss is the detector's. Beside it, per frame: the full detector, the model
// reader on the true corners, and ArUco on the same pose.
//
// With --mismatch it asks instead what the model reader fails to explain when there is nothing to
// explain but the scene: it reads each tag as photographed, on a rendering without noise or JPEG,
// then again with the Bayer mosaic, the phone's processing and the optics removed in turn, and
// reports the residual the model leaves each time. In the held-out world the print (its colour
// error, the label's resampling) stays: it is the scene.

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "cli_values.hpp"
#include "detectors.hpp"
#include "reading/decision.hpp"
#include "reading/model_reader.hpp"
#include "sweep.hpp"

namespace pintag::bench {
namespace {

struct Args {
  SweepOptions sweep;
  int threads = 0;  ///< 0: all cores
  int min_size_px = 24;
  int max_size_px = 48;
  int max_tilt_deg = 72;
  int rivals = 120;  ///< neighbours rendered, nearest first (at most 120)
  bool mismatch = false;
  std::string csv;  ///< a row per tag
};

/// A frame's colour samples as a 4:2:0 JPEG holds them, over one even-aligned box: JFIF luma per
/// pixel, Cb and Cr averaged over each 2 x 2 block.
struct Samples {
  std::vector<float> luma;
  std::vector<float> cb, cr;
};

Samples TakeSamples(const cv::Mat& bgr, const cv::Rect& box) {
  Samples s;
  const auto w = static_cast<std::size_t>(box.width / 2);
  const auto h = static_cast<std::size_t>(box.height / 2);
  s.luma.reserve(static_cast<std::size_t>(box.area()));
  s.cb.assign(w * h, 0.F);
  s.cr.assign(w * h, 0.F);
  for (int y = 0; y < box.height; ++y) {
    const auto* row = bgr.ptr<cv::Vec3b>(box.y + y) + box.x;
    for (int x = 0; x < box.width; ++x) {
      const float b = row[x][0], g = row[x][1], r = row[x][2];
      s.luma.push_back(0.299F * r + 0.587F * g + 0.114F * b);
      const std::size_t block =
          static_cast<std::size_t>(y / 2) * w + static_cast<std::size_t>(x / 2);
      s.cb[block] += 0.25F * (-0.168736F * r - 0.331264F * g + 0.5F * b);
      s.cr[block] += 0.25F * (0.5F * r - 0.418688F * g - 0.081312F * b);
    }
  }
  return s;
}

double SquaredDistance(const std::vector<float>& a, const std::vector<float>& b) {
  double sum = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    sum += static_cast<double>(a[i] - b[i]) * (a[i] - b[i]);
  return sum;
}

/// The noise variance of each kind of sample: the photo against its noise-free rendering.
struct NoiseVariance {
  double luma = 1, chroma = 1;
};

NoiseVariance MeasureNoise(const Samples& photo, const Samples& clean) {
  NoiseVariance v;
  v.luma = std::max(0.25, SquaredDistance(photo.luma, clean.luma) / photo.luma.size());
  v.chroma =
      std::max(0.25, (SquaredDistance(photo.cb, clean.cb) + SquaredDistance(photo.cr, clean.cr)) /
                         (2.0 * photo.cb.size()));
  return v;
}

/// How far a rendering lies from the photo, in noise units (twice the negative log-likelihood
/// under independent Gaussian noise, up to a constant).
double NoiseUnits(const Samples& photo, const Samples& rendering, const NoiseVariance& v) {
  return SquaredDistance(photo.luma, rendering.luma) / v.luma +
         (SquaredDistance(photo.cb, rendering.cb) + SquaredDistance(photo.cr, rendering.cr)) /
             v.chroma;
}

/// Keys whose 15 data bits differ from `key`'s in one place (first) or two.
std::vector<int> NearestKeys(int key) {
  std::vector<int> keys;
  keys.reserve(120);
  for (int i = 0; i < 15; ++i) keys.push_back(key ^ (1 << i));
  for (int i = 0; i < 15; ++i) {
    for (int j = i + 1; j < 15; ++j) keys.push_back(key ^ (1 << i) ^ (1 << j));
  }
  return keys;
}

bool ParseArgs(int argc, char** argv, Args& args) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto next = [&]() -> const char* {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "pintag_genie_probe: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--world") {
      args.sweep.world = WorldOrExit("pintag_genie_probe", next());
    } else if (a == "--seed") {
      args.sweep.seed = SeedOrExit("pintag_genie_probe", next());
    } else if (a == "--frames-per-bin") {
      args.sweep.frames_per_bin =
          IntegerOrExit("pintag_genie_probe", "--frames-per-bin", next(), 1, 100000);
    } else if (a == "--threads") {
      args.threads = IntegerOrExit("pintag_genie_probe", "--threads", next(), 0, 1024);
    } else if (a == "--min-size") {
      args.min_size_px = IntegerOrExit("pintag_genie_probe", "--min-size", next(), 1, 10000);
    } else if (a == "--max-size") {
      args.max_size_px = IntegerOrExit("pintag_genie_probe", "--max-size", next(), 1, 10000);
    } else if (a == "--max-tilt") {
      args.max_tilt_deg = IntegerOrExit("pintag_genie_probe", "--max-tilt", next(), 0, 89);
    } else if (a == "--rivals") {
      args.rivals = IntegerOrExit("pintag_genie_probe", "--rivals", next(), 0, 120);
    } else if (a == "--mismatch") {
      args.mismatch = true;
    } else if (a == "--csv") {
      args.csv = next();
    } else {
      std::fprintf(stderr,
                   "usage: pintag_genie_probe [--world tuning|held-out] [--seed N] "
                   "[--frames-per-bin N] [--min-size PX] [--max-size PX] [--max-tilt DEG] "
                   "[--rivals N | --mismatch] [--threads N] [--csv FILE]\n");
      return false;
    }
  }
  if (const std::string error = TuningToolOptionsError(args.sweep); !error.empty()) {
    std::fprintf(stderr, "pintag_genie_probe: %s\n", error.c_str());
    return false;
  }
  // The CSV is written at the end of a run of many minutes: a path it cannot write is said now.
  if (!args.csv.empty()) {
    FILE* csv = std::fopen(args.csv.c_str(), "a");
    if (csv == nullptr) {
      std::fprintf(stderr, "pintag_genie_probe: cannot write %s\n", args.csv.c_str());
      return false;
    }
    std::fclose(csv);
  }
  return true;
}

/// The scene without sensor noise and without the JPEG, whose quantisation a reader cannot know
/// beforehand and so meets as noise.
scene::SceneSpec Clean(scene::SceneSpec spec) {
  spec.capture.read_noise = 0;
  spec.capture.shot_noise = 0;
  spec.capture.jpeg_quality = 0;
  spec.photometry.noise_sigma = 0;
  spec.photometry.jpeg_quality = 0;
  return spec;
}

/// The box the genie compares: the square and a margin for blur, on the 2 x 2 chroma grid.
cv::Rect GenieBox(const scene::MarkerTruth& truth, const scene::Camera& camera) {
  double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
  for (const cv::Point2d& p : truth.corners_px) {
    x0 = std::min(x0, p.x), y0 = std::min(y0, p.y);
    x1 = std::max(x1, p.x), y1 = std::max(y1, p.y);
  }
  const int left = (static_cast<int>(std::floor(x0)) - 4) & ~1;
  const int top = (static_cast<int>(std::floor(y0)) - 4) & ~1;
  const int right = (static_cast<int>(std::ceil(x1)) + 6) & ~1;
  const int bottom = (static_cast<int>(std::ceil(y1)) + 6) & ~1;
  return cv::Rect(left, top, right - left, bottom - top) &
         cv::Rect(0, 0, camera.width & ~1, camera.height & ~1);
}

reading::ModelReading ReadOnTruth(const cv::Mat& bgr, ChromaUpsampling upsampling,
                                  const scene::MarkerTruth& truth) {
  return reading::ReadThroughModel(
      bgr, upsampling,
      {truth.corners_px[0], truth.corners_px[1], truth.corners_px[2], truth.corners_px[3]});
}

/// Calls `work(i)` for i in [0, count) on `threads` threads (0: all cores), each index once.
template <typename Work>
void OnThreads(int threads, std::size_t count, const Work& work) {
  std::atomic<std::size_t> next{0};
  std::atomic<int> done{0};
  const auto worker = [&] {
    for (std::size_t i; (i = next++) < count;) {
      work(i);
      std::fprintf(stderr, "\r%d / %zu tags", ++done, count);
    }
  };
  if (threads <= 0) threads = static_cast<int>(std::thread::hardware_concurrency());
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  std::fprintf(stderr, "\n");
}

struct TagResult {
  const FrameSpec* frame = nullptr;
  bool judged = false;          ///< the tag was fully visible and the genie judged it
  bool detected = false;        ///< the full detector reported the true key
  bool detector_wrong = false;  ///< … or a wrong one where the tag is
  int reader = 0;               ///< model reader on the true corners: 1 right, -1 wrong, 0 none
  double reader_lead = 0;
  double reader_luma_sigma = 0, reader_chroma_sigma = 0;  ///< its noise units × 255 (luma linear)
  bool aruco = false;                                     ///< ArUco found the same pose's marker
  double genie_margin = 0;  ///< least (neighbour − truth) in noise units; < 0: a neighbour won
  int genie_rival = -1;     ///< that neighbour
  double luma_sigma = 0, chroma_sigma = 0;  ///< the photo's noise, JPEG's included
};

void Judge(const FrameSpec& f, const scene::Camera& camera, int rivals, MarkerDetector& pintag,
           MarkerDetector& aruco, TagResult& r) {
  r.frame = &f;
  const scene::SceneSpec spec = SceneFor(f, Marker::kPinTag, camera);
  const scene::Scene photo = scene::RenderScene(spec);
  const scene::MarkerTruth& truth = photo.truth.front();
  if (!truth.fully_visible) return;

  for (const Found& found : pintag.detect(photo.bgr)) {
    const cv::Point2d c = (found.corners[0] + found.corners[2]) * 0.5;
    const cv::Point2d t = (truth.corners_px[0] + truth.corners_px[2]) * 0.5;
    if (cv::norm(c - t) > truth.square_px / 2) continue;
    (found.id == truth.id ? r.detected : r.detector_wrong) = true;
  }
  const reading::ModelReading m = ReadOnTruth(photo.bgr, ChromaUpsampling::kBoth, truth);
  if (m.decision.winner && reading::RefuseCodeword(m).empty()) {
    r.reader = m.decision.winner->value() == truth.id ? 1 : -1;
  }
  r.reader_lead = m.decision.lead;
  r.reader_luma_sigma = 255 * m.fit.luma_noise;
  r.reader_chroma_sigma = 255 * m.fit.chroma_noise;
  const scene::Scene aruco_photo = scene::RenderScene(SceneFor(f, Marker::kAruco, camera));
  for (const Found& found : aruco.detect(aruco_photo.bgr)) {
    if (found.id == aruco_photo.truth.front().id) r.aruco = true;
  }

  const cv::Rect box = GenieBox(truth, camera);
  const Samples observed = TakeSamples(photo.bgr, box);
  const Samples clean_truth = TakeSamples(scene::RenderScene(Clean(spec)).bgr, box);
  const NoiseVariance noise = MeasureNoise(observed, clean_truth);
  r.judged = true;
  r.luma_sigma = std::sqrt(noise.luma);
  r.chroma_sigma = std::sqrt(noise.chroma);
  const double truth_units = NoiseUnits(observed, clean_truth, noise);
  // No rival rendered (--rivals 0): no margin, and the genie counts nothing.
  r.genie_margin = rivals > 0 ? std::numeric_limits<double>::infinity() : std::nan("");
  const std::vector<int> keys = NearestKeys(truth.id);
  for (const int key : std::span(keys).first(static_cast<std::size_t>(rivals))) {
    FrameSpec rival_frame = f;
    rival_frame.pintag_key = key;
    const scene::Scene rival =
        scene::RenderScene(Clean(SceneFor(rival_frame, Marker::kPinTag, camera)));
    const double margin = NoiseUnits(observed, TakeSamples(rival.bgr, box), noise) - truth_units;
    if (margin < r.genie_margin) r.genie_margin = margin, r.genie_rival = key;
  }
}

int RunGenie(const Args& args, const std::vector<FrameSpec>& frames, const scene::Camera& camera) {
  std::vector<TagResult> results(frames.size());
  OnThreads(args.threads, frames.size(), [&](std::size_t i) {
    thread_local const auto pintag = [&] {
      auto d = MakePinTagDetector(camera);
      d->setThreads(1);
      return d;
    }();
    thread_local const auto aruco = MakeArucoDetector(camera);
    Judge(frames[i], camera, args.rivals, *pintag, *aruco, results[i]);
  });

  if (!args.csv.empty()) {
    FILE* csv = std::fopen(args.csv.c_str(), "w");
    if (csv == nullptr) {
      std::fprintf(stderr, "pintag_genie_probe: cannot write %s\n", args.csv.c_str());
      return 1;
    }
    std::fprintf(csv,
                 "frame,size_px,tilt_deg,hard,truth,detected,detector_wrong,reader,reader_lead,"
                 "reader_luma_sigma,reader_chroma_sigma,aruco,genie_margin,genie_rival,luma_sigma,"
                 "chroma_sigma\n");
    for (const TagResult& r : results) {
      if (!r.judged) continue;
      const FrameSpec& f = *r.frame;
      std::fprintf(csv, "%d,%d,%d,%d,%d,%d,%d,%d,%.1f,%.2f,%.2f,%d,%.1f,%d,%.2f,%.2f\n", f.index,
                   kSizesPx[f.size_index], kTiltsDeg[f.tilt_index], f.hard ? 1 : 0, f.pintag_key,
                   r.detected ? 1 : 0, r.detector_wrong ? 1 : 0, r.reader, r.reader_lead,
                   r.reader_luma_sigma, r.reader_chroma_sigma, r.aruco ? 1 : 0, r.genie_margin,
                   r.genie_rival, r.luma_sigma, r.chroma_sigma);
    }
    std::fclose(csv);
  }

  std::printf("%s world, seed %llu, %d frames per bin, tilts <= %d deg, %d rivals per tag\n",
              ToString(args.sweep.world).c_str(), static_cast<unsigned long long>(args.sweep.seed),
              args.sweep.frames_per_bin, args.max_tilt_deg, args.rivals);
  std::printf("%-9s %5s %5s %6s %8s %8s %10s %10s %10s\n", "light", "size", "tags", "ArUco",
              "PinTag", "reader", "genie>0", "genie>=20", "genie>=50");
  for (int hard = 0; hard < 2; ++hard) {
    for (int s = 0; s < kSizeCount; ++s) {
      int tags = 0, aruco = 0, detected = 0, reader = 0, genie0 = 0, genie20 = 0, genie50 = 0;
      for (const TagResult& r : results) {
        if (!r.judged || r.frame->size_index != s || r.frame->hard != (hard == 1)) continue;
        ++tags;
        aruco += r.aruco ? 1 : 0;
        detected += r.detected ? 1 : 0;
        reader += r.reader == 1 ? 1 : 0;
        genie0 += r.genie_margin > 0 ? 1 : 0;
        genie20 += r.genie_margin >= 20 ? 1 : 0;
        genie50 += r.genie_margin >= 50 ? 1 : 0;
      }
      if (tags == 0) continue;
      std::printf("%-9s %4dpx %5d %6d %8d %8d %10d %10d %10d\n", hard ? "hard" : "moderate",
                  kSizesPx[s], tags, aruco, detected, reader, genie0, genie20, genie50);
    }
  }
  return 0;
}

/// The scene at stage 0 as photographed; from stage 1 without noise or JPEG, then without,
/// cumulatively, 2 the Bayer mosaic, 3 the phone's processing, 4 the optics. Each world's own
/// camera: the tuning world's Photometry, the held-out world's PhoneCapture.
scene::SceneSpec WithoutUpTo(scene::SceneSpec spec, int stage) {
  if (stage == 0) return spec;
  spec = Clean(spec);
  scene::Photometry& p = spec.photometry;
  scene::PhoneCapture& c = spec.capture;
  if (stage >= 2) p.bayer = false, c.mosaic = false;
  if (stage >= 3) {
    p.sharpen = 0, p.tone_gamma = 1, p.saturation = 1, p.chroma_denoise_px = 0;
    c.contrast = 0, c.saturation = 1, c.sharpen_amount = 0;
  }
  if (stage >= 4) {
    p.defocus_sigma_px = 0, p.motion_px = 0;
    c.defocus_sigma_px = 0, c.motion_px = 0;
  }
  return spec;
}

bool HasMosaic(const scene::SceneSpec& spec) {
  return spec.world == scene::World::kTuning ? spec.photometry.bayer : spec.capture.mosaic;
}

int RunMismatch(const Args& args, const std::vector<FrameSpec>& frames,
                const scene::Camera& camera) {
  constexpr int kStages = 5;
  // [frame][stage]: luma and chroma residual, code values; NaN where not fully visible.
  std::vector<std::array<std::array<double, 2>, kStages>> residual(frames.size());
  OnThreads(args.threads, frames.size(), [&](std::size_t i) {
    const scene::SceneSpec spec = SceneFor(frames[i], Marker::kPinTag, camera);
    for (int stage = 0; stage < kStages; ++stage) {
      const scene::Scene clean = scene::RenderScene(WithoutUpTo(spec, stage));
      const scene::MarkerTruth& truth = clean.truth.front();
      // Stage 0 is the photo as saved (4:2:0 JPEG); the later stages have no JPEG.
      const reading::ModelReading m = ReadOnTruth(
          clean.bgr, stage == 0 ? ChromaUpsampling::kBoth : ChromaUpsampling::kNone, truth);
      const bool ok = truth.fully_visible && m.fit.ok;
      residual[i][stage] = {ok ? 255 * m.fit.luma_noise : std::nan(""),
                            ok ? 255 * m.fit.chroma_noise : std::nan("")};
    }
  });
  if (!args.csv.empty()) {
    FILE* csv = std::fopen(args.csv.c_str(), "w");
    if (csv == nullptr) {
      std::fprintf(stderr, "pintag_genie_probe: cannot write %s\n", args.csv.c_str());
      return 1;
    }
    std::fprintf(csv, "frame,size_px,tilt_deg,hard,bayer");
    for (int stage = 0; stage < kStages; ++stage)
      std::fprintf(csv, ",luma%d,chroma%d", stage, stage);
    std::fprintf(csv, "\n");
    for (std::size_t i = 0; i < frames.size(); ++i) {
      const FrameSpec& f = frames[i];
      std::fprintf(csv, "%d,%d,%d,%d,%d", f.index, kSizesPx[f.size_index], kTiltsDeg[f.tilt_index],
                   f.hard ? 1 : 0, HasMosaic(SceneFor(f, Marker::kPinTag, camera)) ? 1 : 0);
      for (const auto& r : residual[i]) std::fprintf(csv, ",%.2f,%.2f", r[0], r[1]);
      std::fprintf(csv, "\n");
    }
    std::fclose(csv);
  }
  std::printf(
      "%s world, seed %llu, %d frames per bin: the model's residual, mean over tags, luma / chroma "
      "(the reader's units x 255: linear luminance, Cb and Cr)\n",
      ToString(args.sweep.world).c_str(), static_cast<unsigned long long>(args.sweep.seed),
      args.sweep.frames_per_bin);
  std::printf("%-9s %5s %5s %14s %14s %14s %14s %14s\n", "light", "size", "tags", "photographed",
              "noise-free", "- Bayer", "- processing", "- optics");
  for (int hard = 0; hard < 2; ++hard) {
    for (int s = 0; s < kSizeCount; ++s) {
      int tags = 0;
      std::array<std::array<double, 2>, kStages> sum{};
      for (std::size_t i = 0; i < frames.size(); ++i) {
        const FrameSpec& f = frames[i];
        if (f.size_index != s || f.hard != (hard == 1) || std::isnan(residual[i][0][0])) continue;
        ++tags;
        for (int stage = 0; stage < kStages; ++stage) {
          sum[stage][0] += residual[i][stage][0], sum[stage][1] += residual[i][stage][1];
        }
      }
      if (tags == 0) continue;
      std::printf("%-9s %4dpx %5d", hard ? "hard" : "moderate", kSizesPx[s], tags);
      for (const auto& v : sum) std::printf("    %5.2f / %5.2f", v[0] / tags, v[1] / tags);
      std::printf("\n");
    }
  }
  return 0;
}

int Main(int argc, char** argv) {
  Args args;
  args.sweep.world = scene::World::kTuning;  // what tuning may look at
  args.sweep.tagless_frames = 0;
  if (!ParseArgs(argc, argv, args)) return 2;
  const scene::Camera camera = CameraFor(args.sweep.world);
  std::vector<FrameSpec> frames = MakeSweep(args.sweep, camera);
  std::erase_if(frames, [&](const FrameSpec& f) {
    return f.tagless() || kSizesPx[f.size_index] > args.max_size_px ||
           kSizesPx[f.size_index] < args.min_size_px || kTiltsDeg[f.tilt_index] > args.max_tilt_deg;
  });
  return args.mismatch ? RunMismatch(args, frames, camera) : RunGenie(args, frames, camera);
}

}  // namespace
}  // namespace pintag::bench

int main(int argc, char** argv) {
  return pintag::bench::Main(argc, argv);
}
