// pintag_reader_probe: the readers alone, on squares placed by the truth. Renders the sweep's
// tagged frames (either world), reads every tag on its true corners (and, with --jitter, on
// corners moved by Gaussian noise), and counts right keys, wrong keys and tags left unread per
// size and photometry. What the detector's readers can do when the candidate stages are perfect:
// the ceiling of recall, and the misreads the readers alone would make.

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "pintag/scene/rng.hpp"
#include "read_tag.hpp"
#include "sweep.hpp"

namespace pintag::bench {
namespace {

struct Args {
  SweepOptions sweep;
  double jitter_px = 0;  ///< standard deviation of the noise on each corner coordinate
  int draws = 1;         ///< readings per tag (1 without jitter)
  int threads = 0;       ///< 0: all cores
  int max_size_px = 48;
  bool verbose = false;  ///< also a line per tag left unread
};

struct Count {
  int right = 0, wrong = 0, unread = 0;
};

int Main(int argc, char** argv) {
  Args args;
  args.sweep.tagless_frames = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto next = [&]() -> const char* {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "pintag_reader_probe: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--world") {
      const std::string w = next();
      args.sweep.world = w == "tuning" ? scene::World::kTuning : scene::World::kHeldOut;
    } else if (a == "--seed") {
      args.sweep.seed = std::strtoull(next(), nullptr, 10);
    } else if (a == "--frames-per-bin") {
      args.sweep.frames_per_bin = std::max(1, std::atoi(next()));
    } else if (a == "--jitter") {
      args.jitter_px = std::atof(next());
    } else if (a == "--draws") {
      args.draws = std::max(1, std::atoi(next()));
    } else if (a == "--threads") {
      args.threads = std::atoi(next());
    } else if (a == "--verbose") {
      args.verbose = true;
    } else if (a == "--max-size") {
      args.max_size_px = std::atoi(next());
    } else {
      std::fprintf(stderr,
                   "usage: pintag_reader_probe [--world held-out|tuning] [--seed N] "
                   "[--frames-per-bin N] [--jitter PX --draws N] [--max-size PX] [--threads N] "
                   "[--verbose]\n");
      return a == "--help" ? 0 : 2;
    }
  }
  const scene::Camera camera = CameraFor(args.sweep.world);
  std::vector<FrameSpec> frames = MakeSweep(args.sweep, camera);
  std::erase_if(frames, [&](const FrameSpec& f) {
    return f.tagless() || kSizesPx[f.size_index] > args.max_size_px;
  });
  // [hard][size][tilt]
  std::vector<Count> counts(2 * kSizeCount * kTiltCount);
  const auto at = [&](const FrameSpec& f) -> Count& {
    return counts[static_cast<std::size_t>((f.hard * kSizeCount + f.size_index) * kTiltCount +
                                           f.tilt_index)];
  };
  std::mutex mutex;
  std::atomic<std::size_t> next{0};
  const auto worker = [&] {
    for (std::size_t i; (i = next++) < frames.size();) {
      const FrameSpec& f = frames[i];
      const scene::Scene s = scene::RenderScene(SceneFor(f, Marker::kPinTag, camera));
      const scene::MarkerTruth& truth = s.truth.front();
      if (!truth.fully_visible) continue;
      scene::Rng rng(f.seed ^ 0x70726F6265ULL);
      for (int d = 0; d < (args.jitter_px > 0 ? args.draws : 1); ++d) {
        stage::Quad quad;
        for (std::size_t c = 0; c < 4; ++c) {
          quad[c] = truth.corners_px[c] +
                    cv::Point2d(rng.normal() * args.jitter_px, rng.normal() * args.jitter_px);
        }
        const stage::CandidateReading r = stage::ReadCandidate(s.bgr, quad, {});
        const std::lock_guard lock(mutex);
        Count& c = at(f);
        if (!r.reading.payload.key) {
          ++c.unread;
          if (args.verbose) {
            const auto& n = r.reading.nearest;
            std::printf(
                "unread f%d %dpx %ddeg %s truth %d: fit %d sigma %.2fx%.2f chroma+%.2f rms %.4f; "
                "nearest %d lead %.1f excess %.1f err '%s' orient '%s' payload '%s'\n",
                f.index, kSizesPx[f.size_index], kTiltsDeg[f.tilt_index], f.hard ? "hard" : "mod",
                truth.id, r.reading.fit.ok, r.reading.fit.sigma_major_px,
                r.reading.fit.sigma_minor_px, r.reading.fit.chroma_extra_px, r.reading.fit.rms,
                n.winner ? n.winner->value() : -1, n.lead, n.excess, n.error.c_str(),
                r.reading.orientation.error.c_str(), r.reading.payload.error.c_str());
          }
        } else if (r.reading.payload.key->value() == truth.id) {
          ++c.right;
        } else {
          ++c.wrong;
          std::printf("WRONG frame %d (%d px, %d deg, %s): read %d for %d\n", f.index,
                      kSizesPx[f.size_index], kTiltsDeg[f.tilt_index], f.hard ? "hard" : "mod",
                      r.reading.payload.key->value(), truth.id);
        }
      }
    }
  };
  const int threads =
      args.threads > 0 ? args.threads : static_cast<int>(std::thread::hardware_concurrency());
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();

  std::printf(
      "%s world, seed %llu, %d frames per bin, jitter %.2f px x %d: right / wrong / unread\n",
      ToString(args.sweep.world).c_str(), static_cast<unsigned long long>(args.sweep.seed),
      args.sweep.frames_per_bin, args.jitter_px, args.jitter_px > 0 ? args.draws : 1);
  for (int hard = 0; hard < 2; ++hard) {
    std::printf("%s\n  size  ", hard ? "hard" : "moderate");
    for (int t = 0; t < kTiltCount; ++t) std::printf("%9d°", kTiltsDeg[t]);
    std::printf("   | <=72° right/all  wrong\n");
    for (int s = 0; s < kSizeCount; ++s) {
      if (kSizesPx[s] > args.max_size_px) continue;
      std::printf("  %3dpx ", kSizesPx[s]);
      int right = 0, all = 0, wrong = 0;
      for (int t = 0; t < kTiltCount; ++t) {
        const Count& c = counts[static_cast<std::size_t>((hard * kSizeCount + s) * kTiltCount + t)];
        std::printf(" %3d/%-2d/%-2d", c.right, c.wrong, c.unread);
        if (kTiltsDeg[t] <= 72) {
          right += c.right, all += c.right + c.wrong + c.unread, wrong += c.wrong;
        }
      }
      std::printf("   | %4d/%-4d %5d\n", right, all, wrong);
    }
  }
  return 0;
}

}  // namespace
}  // namespace pintag::bench

int main(int argc, char** argv) {
  return pintag::bench::Main(argc, argv);
}
