// pintag_bench: PinTag against ArUco and AprilTag on the same rendered poses, in one process
// (issue 6; docs/BENCHMARKS.md says how to run it and what each column means).

#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cli_values.hpp"
#include "detectors.hpp"
#include "explain.hpp"
#include "machine.hpp"
#include "metrics.hpp"
#include "pintag/detector/json.hpp"
#include "progress.hpp"
#include "report.hpp"
#include "sweep.hpp"

namespace pintag::bench {
namespace {

using Clock = std::chrono::steady_clock;

double Ms(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double, std::milli>(to - from).count();
}

/// CPU time of the calling thread, ms. With one thread every detector works in the caller, so this
/// is its time without what other processes on the machine took.
double ThreadCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

struct Args {
  SweepOptions sweep;
  std::string out_dir = PINTAG_SOURCE_DIR "/docs";
  std::string csv;
  bool all_cores = true;
  int all_cores_every = 2;  ///< the all-cores pass times every this-many-th chunk (1 in --quick)
  bool require_zero_misreads = false;
  bool explain_misses = true;  ///< ExplainMiss on every missed tag (a second detect call)
  bool quiet = false;
  std::string detectors = "pintag,aruco,apriltag-d1,apriltag-d2";
  std::string pintag_options;    ///< JSON object of DetectorOptions fields, for tuning runs
  std::string dump_misses;       ///< directory for crops of the tags PinTag missed
  std::string save_frames;       ///< directory for every PinTag (and tagless) frame as rendered
  std::vector<int> only_frames;  ///< --frame: these frames of the sweep alone (reproducing one)
  int chunk = 24;
};

void Usage(FILE* to) {
  std::fprintf(
      to,
      "usage: pintag_bench [options]\n"
      "  --quick               one frame per size x tilt bin, 6 tagless (CI, about a minute)\n"
      "  --frames-per-bin N    frames per size x tilt x photometry bin (default 8)\n"
      "  --tagless N           tagless photograph frames (default 64)\n"
      "  --seed N              base seed of the sweep (default 1)\n"
      "  --world W             held-out (default), tuning, or blind (run whole when an issue "
      "about\n"
      "                        the detector ends; docs/BENCHMARKS.md): which world's scenes\n"
      "  --jpeg-quality N      save every frame at JPEG quality N (1-100) instead of the "
      "quality its light draws\n"
      "  --jpeg-chroma C       420 (default, as phones save) or 444: JPEG colour resolution "
      "(held-out world)\n"
      "  --no-mosaic           a sensor without a colour filter array (held-out world; analysis)\n"
      "  --sensor-scale K      a sensor of K x the output's resolution, demosaiced there and "
      "scaled\n"
      "                        down (1-4; held-out world; analysis)\n"
      "  --s-curve             give every frame's phone an S-shaped tone curve (tuning world)\n"
      "  --vng-demosaic        give every frame's phone a colour filter array demosaiced by VNG "
      "(tuning world)\n"
      "  --out DIR             where BENCHMARKS.md and images/ go (default: the source "
      "tree's docs/)\n"
      "  --csv FILE            also write one row per frame and detector\n"
      "  --one-thread-only     skip the all-cores pass\n"
      "  --all-cores-every N   time the all-cores pass on every N-th chunk of 24 frames "
      "(default 2; 1 with --quick)\n"
      "  --require-zero-misreads  exit 3 when PinTag misreads a tag or reports one where "
      "there is none (away from the tag, or on a tagless frame)\n"
      "  --detectors LIST      which of pintag,aruco,apriltag-d1,apriltag-d2 to run (default "
      "all; PinTag always runs)\n"
      "  --pintag-options JSON DetectorOptions fields for PinTag, e.g. '{\"red_min_a\":15}' "
      "(tuning; the report says so)\n"
      "  --dump-misses DIR     write a PNG crop of every tag PinTag missed, named by bin and "
      "the stage that lost it\n"
      "  --save-frames DIR     write every PinTag and tagless frame as rendered (PNG)\n"
      "  --frame N             run frame N of the sweep alone (repeatable): a long run's miss or\n"
      "                        misread again, with the other options the run had\n"
      "  --no-explain          skip the per-miss diagnosis (long misread runs: it detects again)\n"
      "  --quiet               no progress on stderr\n");
}

bool ParseArgs(int argc, char** argv, Args* args) {
  bool frames_per_bin_given = false;
  bool tagless_given = false;
  bool all_cores_every_given = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto value = [&](const char* name) -> const char* {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "pintag_bench: %s needs a value\n", name);
        return nullptr;
      }
      return argv[++i];
    };
    // An option's whole value as an integer in [lowest, highest], or a message and false.
    const auto integer = [&](const char* name, long lowest, long highest, int* out) {
      const char* v = value(name);
      if (v == nullptr) return false;
      char* end = nullptr;
      const long parsed = std::strtol(v, &end, 10);
      if (end == v || *end != '\0' || parsed < lowest || parsed > highest) {
        std::fprintf(stderr, "pintag_bench: %s is %ld to %ld\n", name, lowest, highest);
        return false;
      }
      *out = static_cast<int>(parsed);
      return true;
    };
    if (a == "--quick") {
      args->sweep.quick = true;
    } else if (a == "--frames-per-bin") {
      if (!integer("--frames-per-bin", 1, 100000, &args->sweep.frames_per_bin)) return false;
      frames_per_bin_given = true;
    } else if (a == "--tagless") {
      if (!integer("--tagless", 0, 1000000, &args->sweep.tagless_frames)) return false;
      tagless_given = true;
    } else if (a == "--seed") {
      const char* v = value("--seed");
      if (v == nullptr) return false;
      args->sweep.seed = SeedOrExit("pintag_bench", v);
    } else if (a == "--world") {
      const char* v = value("--world");
      if (v == nullptr) return false;
      args->sweep.world = WorldOrExit("pintag_bench", v);
    } else if (a == "--jpeg-quality") {
      if (!integer("--jpeg-quality", 1, 100, &args->sweep.jpeg_quality)) return false;
    } else if (a == "--jpeg-chroma") {
      const char* v = value("--jpeg-chroma");
      if (v == nullptr) return false;
      const std::string chroma = v;
      if (chroma != "420" && chroma != "444") {
        std::fprintf(stderr, "pintag_bench: --jpeg-chroma is 420 or 444\n");
        return false;
      }
      args->sweep.jpeg_full_chroma = chroma == "444";
    } else if (a == "--no-mosaic") {
      args->sweep.no_mosaic = true;
    } else if (a == "--sensor-scale") {
      if (!integer("--sensor-scale", 1, 4, &args->sweep.sensor_scale)) return false;
    } else if (a == "--s-curve") {
      args->sweep.s_curve = true;
    } else if (a == "--vng-demosaic") {
      args->sweep.vng_demosaic = true;
    } else if (a == "--out") {
      const char* v = value("--out");
      if (v == nullptr) return false;
      args->out_dir = v;
    } else if (a == "--csv") {
      const char* v = value("--csv");
      if (v == nullptr) return false;
      args->csv = v;
    } else if (a == "--all-cores-every") {
      if (!integer("--all-cores-every", 1, 100000, &args->all_cores_every)) return false;
      all_cores_every_given = true;
    } else if (a == "--one-thread-only") {
      args->all_cores = false;
    } else if (a == "--require-zero-misreads") {
      args->require_zero_misreads = true;
    } else if (a == "--detectors") {
      const char* v = value("--detectors");
      if (v == nullptr) return false;
      args->detectors = v;
      // An unknown name was skipped without a word: a typo ran a sweep without its peer.
      std::stringstream names(args->detectors);
      for (std::string name; std::getline(names, name, ',');) {
        if (name != "pintag" && name != "aruco" && name != "apriltag-d1" && name != "apriltag-d2") {
          std::fprintf(stderr,
                       "pintag_bench: --detectors: unknown detector \"%s\" (pintag, aruco, "
                       "apriltag-d1, apriltag-d2)\n",
                       name.c_str());
          return false;
        }
      }
    } else if (a == "--pintag-options") {
      const char* v = value("--pintag-options");
      if (v == nullptr) return false;
      args->pintag_options = v;
    } else if (a == "--dump-misses") {
      const char* v = value("--dump-misses");
      if (v == nullptr) return false;
      args->dump_misses = v;
    } else if (a == "--save-frames") {
      const char* v = value("--save-frames");
      if (v == nullptr) return false;
      args->save_frames = v;
    } else if (a == "--frame") {
      const char* v = value("--frame");
      if (v == nullptr) return false;
      char* end = nullptr;
      const long n = std::strtol(v, &end, 10);
      if (*v == '\0' || *end != '\0' || n < 0 || n > 10'000'000) {
        std::fprintf(stderr, "pintag_bench: --frame needs a frame number, not %s\n", v);
        return false;
      }
      args->only_frames.push_back(static_cast<int>(n));
    } else if (a == "--no-explain") {
      args->explain_misses = false;
    } else if (a == "--quiet") {
      args->quiet = true;
    } else if (a == "--help" || a == "-h") {
      Usage(stdout);
      std::exit(0);
    } else {
      std::fprintf(stderr, "pintag_bench: unknown option %s\n", a.c_str());
      Usage(stderr);
      return false;
    }
  }
  // --quick draws one frame per bin and at most 6 tagless, and times every chunk on all cores:
  // a count given beside it was ignored.
  if (args->sweep.quick) {
    for (const auto& [given, why] :
         {std::pair{frames_per_bin_given, "runs one frame per bin; drop --frames-per-bin"},
          std::pair{tagless_given && args->sweep.tagless_frames > 6,
                    "runs at most 6 tagless frames; drop --tagless or give 0 to 6"},
          std::pair{all_cores_every_given && args->all_cores_every != 1,
                    "times every chunk on all cores; drop --all-cores-every"}}) {
      if (given) {
        std::fprintf(stderr, "pintag_bench: --quick %s\n", why);
        return false;
      }
    }
  }
  if (const std::string error = SweepOptionsError(args->sweep); !error.empty()) {
    std::fprintf(stderr, "pintag_bench: %s\n", error.c_str());
    return false;
  }
  // The blind world stays blind only while no one tunes on it or studies what it misses.
  if (args->sweep.world == scene::World::kBlind) {
    for (const auto& [given, option] :
         {std::pair{!args->pintag_options.empty(), "--pintag-options"},
          std::pair{!args->dump_misses.empty(), "--dump-misses"},
          std::pair{!args->save_frames.empty(), "--save-frames"},
          std::pair{!args->only_frames.empty(), "--frame"},
          std::pair{frames_per_bin_given || tagless_given, "a sweep of another size"}}) {
      if (given) {
        std::fprintf(stderr,
                     "pintag_bench: %s is for tuning and study, and the blind world is neither: "
                     "it is run whole (use --world held-out or tuning)\n",
                     option);
        return false;
      }
    }
  }
  return true;
}

/// A frame rendered once per marker (a tagless frame once, shared by all).
struct Rendered {
  std::array<cv::Mat, kMarkerCount> bgr;
  std::array<std::vector<scene::MarkerTruth>, kMarkerCount> truth;
  const cv::Mat& image(const FrameSpec& f, Marker m) const {
    return bgr[f.tagless() ? 0 : static_cast<int>(m)];
  }
  const std::vector<scene::MarkerTruth>& truthFor(const FrameSpec& f, Marker m) const {
    return truth[f.tagless() ? 0 : static_cast<int>(m)];
  }
};

// A crop around the missed tag (its quiet zone and some background) as it is, for re-running the
// detector on, and enlarged 4x with nearest neighbour so that single pixels stay visible. Beside
// the crop, its truth in the form of tests/data/regressions/ (key, corners in crop pixels), so a
// miss or misread worth keeping can be committed as it is. The crop starts on even pixels, which
// keeps a 4:2:0 frame's chroma blocks where the frame had them.
void DumpMiss(const std::string& dir, const FrameSpec& f, const cv::Mat& bgr,
              const scene::MarkerTruth& truth, const std::string& why, const std::string& run) {
  cv::Rect box =
      cv::boundingRect(std::vector<cv::Point2f>(truth.corners_px.begin(), truth.corners_px.end()));
  const int pad = static_cast<int>(truth.square_px * 0.5) + 4;
  const int x0 = std::max(0, (box.x - pad) & ~1), y0 = std::max(0, (box.y - pad) & ~1);
  box = cv::Rect(x0, y0, box.x + box.width + pad - x0, box.y + box.height + pad - y0) &
        cv::Rect(0, 0, bgr.cols, bgr.rows);
  cv::Mat enlarged;
  cv::resize(bgr(box), enlarged, {}, 4, 4, cv::INTER_NEAREST);
  std::string reason = why.substr(0, why.find(':'));
  for (char& c : reason) {
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '-';
  }
  char name[256];
  std::snprintf(name, sizeof name, "%s/%03dpx-%02ddeg-%s-f%04d-key%d-%s", dir.c_str(),
                kSizesPx[static_cast<std::size_t>(f.size_index)],
                kTiltsDeg[static_cast<std::size_t>(f.tilt_index)], f.hard ? "hard" : "mod", f.index,
                truth.id, reason.c_str());
  const std::string base = name;
  cv::imwrite(base + ".png", bgr(box));
  cv::imwrite(base + "-x4.png", enlarged);
  nlohmann::json corners = nlohmann::json::array();
  for (const cv::Point2d& c : truth.corners_px) {
    const auto at = [](double v) { return std::round(v * 100) / 100; };
    corners.push_back({at(c.x - box.x), at(c.y - box.y)});
  }
  const nlohmann::json sidecar = {
      {"key", truth.id},
      {"corners", corners},
      {"square_offsets", {{0, 0}, {0, 0}, {0, 0}, {0, 0}}},
      {"source", run + ", frame " + std::to_string(f.index) + ", cropped at (" +
                     std::to_string(box.x) + ", " + std::to_string(box.y) + ")"},
      {"note", why},
  };
  std::ofstream(base + ".json") << sidecar.dump(2) << '\n';
}

struct CsvRow {
  int frame = 0;
  int detector = 0;
  Outcome outcome;
  double time_one = kNaN;
  double time_all = kNaN;
};

int Main(int argc, char** argv) {
  Args args;
  if (!ParseArgs(argc, argv, &args)) return 2;
  // Every output place is made or checked before the sweep, which can take many minutes.
  const std::string csv_dir =
      args.csv.empty() ? "" : std::filesystem::path(args.csv).parent_path().string();
  for (const std::string& dir : {args.dump_misses, args.save_frames, args.out_dir, csv_dir}) {
    if (dir.empty()) continue;
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) {
      std::fprintf(stderr, "pintag_bench: cannot create %s: %s\n", dir.c_str(),
                   ec.message().c_str());
      return 2;
    }
  }
  // A directory that exists may still refuse files: asked now, not after the sweep.
  const std::string csv_place = args.csv.empty() ? "" : csv_dir.empty() ? "." : csv_dir;
  for (const std::string& dir : {args.out_dir, csv_place}) {
    if (!dir.empty() && ::access(dir.c_str(), W_OK) != 0) {
      std::fprintf(stderr, "pintag_bench: cannot write in %s: %s\n", dir.c_str(),
                   std::strerror(errno));
      return 2;
    }
  }
  const auto wall_start = Clock::now();

  BenchResult result;
  result.machine = GatherMachineInfo(PINTAG_SOURCE_DIR);
  for (int i = 0; i < argc; ++i) result.command_line += (i ? " " : "") + std::string(argv[i]);
  result.sweep = args.sweep;
  result.chosen_frames_only = !args.only_frames.empty();
  result.photos = static_cast<int>(scene::BackgroundPhotos(args.sweep.world).size());
  result.camera = CameraFor(args.sweep.world);
  const scene::Camera camera = result.camera;
  const std::vector<FrameSpec> frames = [&] {
    std::vector<FrameSpec> all = MakeSweep(args.sweep, camera);
    if (args.only_frames.empty()) return all;
    std::vector<FrameSpec> kept;
    for (const int n : args.only_frames) {
      const auto it =
          std::find_if(all.begin(), all.end(), [&](const FrameSpec& f) { return f.index == n; });
      if (it != all.end()) kept.push_back(*it);
    }
    return kept;
  }();
  if (frames.empty()) {
    std::fprintf(stderr, "pintag_bench: no frame of this sweep has the number given to --frame\n");
    return 2;
  }
  for (const FrameSpec& f : frames) (f.tagless() ? result.tagless_frames : result.tagged_frames)++;
  const int cores = std::max(1, result.machine.cores);
  result.all_cores = args.all_cores ? cores : 0;
  result.all_cores_every = args.all_cores_every;

  std::vector<std::unique_ptr<MarkerDetector>> detectors;
  const auto wanted = [&](const std::string& key) {
    return ("," + args.detectors + ",").find("," + key + ",") != std::string::npos;
  };
  DetectorOptions pintag_options;
  if (!args.pintag_options.empty()) {
    std::string error;
    const nlohmann::json json = nlohmann::json::parse(args.pintag_options, nullptr, false);
    if (json.is_discarded() || !OptionsFromJson(json, &pintag_options, &error)) {
      std::fprintf(stderr, "pintag_bench: --pintag-options: %s\n",
                   json.is_discarded() ? "not valid JSON" : error.c_str());
      return 2;
    }
    // The sweep sets these itself for every detector alike (its threads pass by pass, its camera,
    // its 50 mm square): a value given here was overwritten.
    for (const char* field : {"threads", "intrinsics", "tag_size_m"}) {
      if (json.contains(field)) {
        std::fprintf(stderr,
                     "pintag_bench: --pintag-options: \"%s\" is the sweep's to set, not an "
                     "option of a run\n",
                     field);
        return 2;
      }
    }
  }
  const ChromaUpsampling frames_upsampling =
      args.sweep.jpeg_full_chroma ? ChromaUpsampling::kNone : ChromaUpsampling::kBoth;
  detectors.push_back(
      MakePinTagDetector(camera, pintag_options, !args.pintag_options.empty(), frames_upsampling));
  if (wanted("aruco")) detectors.push_back(MakeArucoDetector(camera));
  if (wanted("apriltag-d1")) detectors.push_back(MakeAprilTagDetector(camera, 1));
  if (wanted("apriltag-d2")) detectors.push_back(MakeAprilTagDetector(camera, 2));
  for (const auto& d : detectors) {
    MarkerStats s;
    s.name = d->name();
    s.description = d->description();
    s.marker = d->marker();
    result.markers.push_back(std::move(s));
  }
  std::array<bool, kMarkerCount> needed{};  // markers some detector looks for: rendered
  for (const auto& d : detectors) needed[static_cast<std::size_t>(d->marker())] = true;
  std::vector<CsvRow> rows;
  if (!args.csv.empty()) rows.resize(frames.size() * detectors.size());

  std::fprintf(
      stderr, "pintag_bench: %d tagged + %d tagless frames, %dx%d, %zu detectors, 1 thread%s\n",
      result.tagged_frames, result.tagless_frames, camera.width, camera.height, detectors.size(),
      args.all_cores ? (" then " + std::to_string(cores) + " threads").c_str() : "");
  Progress progress(frames.size() * 2, args.quiet);
  std::size_t done = 0;
  std::mutex progress_mutex;
  bool warmed_up = false;
  int last_threads = 1;
  cv::Mat gray;

  for (std::size_t begin = 0; begin < frames.size();
       begin += static_cast<std::size_t>(args.chunk)) {
    const std::size_t end = std::min(frames.size(), begin + static_cast<std::size_t>(args.chunk));
    // 1. Render the chunk (not timed), on every core.
    cv::setNumThreads(1);
    std::vector<Rendered> rendered(end - begin);
    std::atomic<std::size_t> next{begin};
    // A photograph that cannot be read throws in a worker: kept, the others stopped, and thrown
    // again here (uncaught on its thread it ended the process with no message).
    std::exception_ptr render_error;
    std::mutex render_error_mutex;
    const auto render_frames = [&] {
      for (std::size_t i; (i = next++) < end;) {
        const FrameSpec& f = frames[i];
        for (int m = 0; m < (f.tagless() ? 1 : kMarkerCount); ++m) {
          if (!f.tagless() && !needed[static_cast<std::size_t>(m)]) continue;
          scene::Scene s = scene::RenderScene(SceneFor(f, static_cast<Marker>(m), camera));
          if (!args.save_frames.empty() && m == 0) {
            char name[512];
            std::snprintf(name, sizeof name, "%s/f%05d-%s.png", args.save_frames.c_str(), f.index,
                          f.tagless()
                              ? "tagless"
                              : (std::to_string(kSizesPx[f.size_index]) + "px-" +
                                 std::to_string(kTiltsDeg[f.tilt_index]) + "deg-" +
                                 (f.hard ? "hard" : "mod") + "-key" + std::to_string(f.pintag_key))
                                    .c_str());
            cv::imwrite(name, s.bgr);
          }
          rendered[i - begin].bgr[m] = std::move(s.bgr);
          rendered[i - begin].truth[m] = std::move(s.truth);
        }
        const std::lock_guard lock(progress_mutex);
        progress.update(++done, "rendering");
      }
    };
    const auto render_worker = [&] {
      try {
        render_frames();
      } catch (...) {
        const std::lock_guard lock(render_error_mutex);
        if (!render_error) render_error = std::current_exception();
        next = end;
      }
    };
    std::vector<std::thread> pool;
    for (int t = 1; t < cores; ++t) pool.emplace_back(render_worker);
    render_worker();
    for (std::thread& t : pool) t.join();
    if (render_error) std::rethrow_exception(render_error);

    // 2. Time every detector over the chunk: one thread, then all cores. The order of the
    // detectors turns from chunk to chunk so none always runs first on a cold cache.
    const std::size_t turn = (begin / static_cast<std::size_t>(args.chunk)) % detectors.size();

    const std::size_t chunk_index = begin / static_cast<std::size_t>(args.chunk);
    const int every = args.sweep.quick ? 1 : args.all_cores_every;
    const bool time_all_cores =
        args.all_cores && chunk_index % static_cast<std::size_t>(every) == 0;
    for (int pass = 0; pass < (time_all_cores ? 2 : 1); ++pass) {
      const int threads = pass == 0 ? 1 : cores;
      cv::setNumThreads(threads);
      for (auto& d : detectors) d->setThreads(threads);
      if (!warmed_up || threads != last_threads) {
        // First use allocates (dictionaries, tables), and a new thread count makes libapriltag
        // rebuild its worker pool: warm-up calls, not part of any frame's time.
        for (auto& d : detectors) {
          const FrameSpec& f = frames[begin];
          for (int k = 0; k < (warmed_up ? 1 : 2); ++k)
            d->detect(rendered[0].image(f, d->marker()));
        }
        GrayFloor(rendered[0].bgr[0], &gray);
        last_threads = threads;
      }
      for (std::size_t i = begin; i < end; ++i) {
        const double c0 = ThreadCpuMs();
        const auto t0 = Clock::now();
        GrayFloor(rendered[i - begin].bgr[0], &gray);
        (pass == 0 ? result.floor_ms_one_thread : result.floor_ms_all_cores)
            .push_back(Ms(t0, Clock::now()));
        if (pass == 0) result.floor_cpu_ms_one_thread.push_back(ThreadCpuMs() - c0);
      }
      for (std::size_t k = 0; k < detectors.size(); ++k) {
        const std::size_t di = (k + turn) % detectors.size();
        MarkerDetector& d = *detectors[di];
        MarkerStats& stats = result.markers[di];
        for (std::size_t i = begin; i < end; ++i) {
          const FrameSpec& f = frames[i];
          const Rendered& r = rendered[i - begin];
          const double c0 = ThreadCpuMs();
          const auto t0 = Clock::now();
          const std::vector<Found> found = d.detect(r.image(f, d.marker()));
          const double ms = Ms(t0, Clock::now());
          const double cpu_ms = ThreadCpuMs() - c0;
          if (pass == 1) {
            stats.time_ms_all_cores.push_back(ms);
            if (!rows.empty()) rows[i * detectors.size() + di].time_all = ms;
            continue;
          }
          stats.time_ms_one_thread.push_back(ms);
          stats.cpu_ms_one_thread.push_back(cpu_ms);
          const Outcome outcome = Score(f, r.truthFor(f, d.marker()), found);
          stats.add(f, outcome);
          if (d.marker() == Marker::kPinTag && outcome.counted && !outcome.found &&
              args.explain_misses) {
            const std::string why =
                ExplainMiss(r.image(f, d.marker()), frames_upsampling,
                            r.truthFor(f, d.marker()).front(), camera, pintag_options);
            ++stats.misses[why][f.hard][static_cast<std::size_t>(f.size_index)];
            if (!args.dump_misses.empty()) {
              DumpMiss(args.dump_misses, f, r.image(f, d.marker()),
                       r.truthFor(f, d.marker()).front(), why, result.command_line);
            }
          }
          if (d.marker() == Marker::kPinTag && !args.dump_misses.empty() &&
              outcome.misreads + outcome.off_tag + outcome.false_positives > 0) {
            // The whole frame: a wrong answer has to be reproduced with `pintag detect`.
            char name[256];
            std::snprintf(name, sizeof name, "%s/wrong-f%04d.png", args.dump_misses.c_str(),
                          f.index);
            cv::imwrite(name, r.image(f, d.marker()));
          }
          const auto stages = d.lastStageTimes();
          if (!stages.empty()) {
            if (stats.stage_names.empty()) {
              for (const auto& [name, v] : stages) stats.stage_names.push_back(name);
              stats.stage_ms.resize(stages.size());
            }
            for (std::size_t s = 0; s < stages.size(); ++s) {
              stats.stage_ms[s].push_back(stages[s].second);
            }
          }
          if (!rows.empty()) {
            rows[i * detectors.size() + di] = {static_cast<int>(i), static_cast<int>(di), outcome,
                                               ms, kNaN};
          }
        }
      }
      warmed_up = true;
      cv::setNumThreads(1);
    }
    done += end - begin;
    progress.update(done, "detecting");
  }
  result.machine.load_end = LoadAverage();
  result.wall_seconds = std::chrono::duration<double>(Clock::now() - wall_start).count();

  const MarkerStats& pintag = result.markers[0];
  std::array<char, 64> aruco{};
  if (result.markers.size() > 1 && result.markers[1].name == "ArUco") {
    std::snprintf(aruco.data(), aruco.size(), " (ArUco %.2f ms)",
                  Mean(result.markers[1].time_ms_one_thread));
  }
  char summary[256];
  std::snprintf(summary, sizeof summary,
                "%zu frames; PinTag recall %.1f %%, misreads %d, off-tag detections %d, tagless "
                "false positives %d, mean %.2f ms%s",
                frames.size(), pintag.recall(-1, -1, -1).percent(), pintag.misreads, pintag.off_tag,
                pintag.false_positives, Mean(pintag.time_ms_one_thread), aruco.data());
  progress.finish(summary);

  std::string error;
  if (!WriteReport(result, args.out_dir, &error)) {
    std::fprintf(stderr, "pintag_bench: %s\n", error.c_str());
    return 1;
  }
  std::fprintf(stderr, "pintag_bench: wrote %s/BENCHMARKS.md and %s/images/bench-*.png\n",
               args.out_dir.c_str(), args.out_dir.c_str());
  if (!args.csv.empty()) {
    std::ofstream csv(args.csv);
    csv << "frame,size_px,tilt_deg,photometry,detector,counted,found,misreads,off_tag,"
           "false_positives,"
           "corner_error_px,rotation_error_deg,translation_error_pct,time_ms_1_thread,"
           "time_ms_all_cores\n";
    for (const CsvRow& row : rows) {
      const FrameSpec& f = frames[static_cast<std::size_t>(row.frame)];
      csv << f.index << ',' << (f.tagless() ? 0 : kSizesPx[f.size_index]) << ','
          << (f.tagless() ? -1 : kTiltsDeg[f.tilt_index]) << ',' << (f.hard ? "hard" : "moderate")
          << ',' << detectors[static_cast<std::size_t>(row.detector)]->name() << ','
          << row.outcome.counted << ',' << row.outcome.found << ',' << row.outcome.misreads << ','
          << row.outcome.off_tag << ',' << row.outcome.false_positives << ','
          << row.outcome.corner_error_px << ',' << row.outcome.rotation_error_deg << ','
          << row.outcome.translation_error_pct << ',' << row.time_one << ',' << row.time_all
          << '\n';
    }
    if (!csv) {
      std::fprintf(stderr, "pintag_bench: cannot write %s\n", args.csv.c_str());
      return 1;
    }
  }
  if (args.require_zero_misreads &&
      (pintag.misreads > 0 || pintag.off_tag > 0 || pintag.false_positives > 0)) {
    std::fprintf(stderr,
                 "pintag_bench: PinTag misread %d tags, reported %d tags away from the tag on "
                 "tagged frames and %d on tagless frames\n",
                 pintag.misreads, pintag.off_tag, pintag.false_positives);
    return 3;
  }
  return 0;
}

}  // namespace
}  // namespace pintag::bench

int main(int argc, char** argv) {
  try {
    return pintag::bench::Main(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pintag_bench: %s\n", e.what());
    return 1;
  }
}
