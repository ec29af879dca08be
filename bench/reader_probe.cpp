// pintag_reader_probe: the readers alone, on squares placed by the truth. Renders the sweep's
// tagged frames (either world), reads every tag on its true corners (and, with --jitter, on
// corners moved by Gaussian noise), and counts right keys, wrong keys and tags left unread per
// size and photometry. What the detector's readers can do when the candidate stages are perfect:
// the ceiling of recall, and the misreads the readers alone would make.

#include <time.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "cli_values.hpp"
#include "homography.hpp"
#include "lead_tail.hpp"
#include "pintag/scene/rng.hpp"
#include "reading/codeword_search.hpp"
#include "reading/decision.hpp"
#include "reading/model_reader.hpp"
#include "reading/read_tag.hpp"
#include "reading/region_fit.hpp"
#include "reading/region_system.hpp"
#include "sweep.hpp"

namespace pintag::bench {
namespace {

struct Args {
  SweepOptions sweep;
  double jitter_px = 0;  ///< standard deviation of the noise on each corner coordinate
  int draws = 1;         ///< readings per tag (1 without jitter)
  int threads = 0;       ///< 0: all cores
  int max_size_px = 48;
  int frame = -1;         ///< only this frame of the sweep (its index in the CSV); -1: all
  bool verbose = false;   ///< also a line per tag left unread
  bool model = false;     ///< the model reader (reading/model_reader.hpp) instead of ReadCandidate
  std::string csv;        ///< a row per reading
  std::string residuals;  ///< with --reader model: a picture of each tag and its luma residual
};

// The tag (left) and what the model leaves of its luminance (right, ×1000 around grey), ×8.
void WriteResidual(const std::string& dir, const std::string& name, const cv::Mat& bgr,
                   const reading::ModelFit& fit) {
  const cv::Matx33d h =
      stage::HomographyFromQuad({fit.corners[0], fit.corners[1], fit.corners[2], fit.corners[3]});
  const reading::TagSamples samples = reading::SampleTag(bgr, ChromaUpsampling::kBoth, h);
  if (samples.luma.empty()) return;
  const reading::RegionCoverage coverage(h, reading::CoverageBox(samples.bounds));
  const reading::Kernel kernel = reading::MakeKernel(fit.luma_blur);
  const reading::FreeFit<1> free =
      reading::SolveFree(reading::AccumulateLuma(coverage, samples.luma, kernel));
  const std::vector<double> predicted =
      reading::PredictLuma(coverage, samples.luma, kernel, free.colour[0]);
  const cv::Rect box = cv::Rect(samples.bounds.x - 2, samples.bounds.y - 2,
                                samples.bounds.width + 4, samples.bounds.height + 4) &
                       cv::Rect(0, 0, bgr.cols, bgr.rows);
  cv::Mat residual(box.size(), CV_8UC3, cv::Scalar(128, 128, 128));
  for (std::size_t i = 0; i < samples.luma.size(); ++i) {
    const auto& s = samples.luma[i];
    const int v = std::clamp(static_cast<int>(128 + 1000 * (s.value - predicted[i])), 0, 255);
    residual.at<cv::Vec3b>(s.y - box.y, s.x - box.x) = cv::Vec3b(v, v, v);
  }
  cv::Mat both;
  cv::hconcat(bgr(box), residual, both);
  cv::resize(both, both, {}, 8, 8, cv::INTER_NEAREST);
  cv::imwrite(dir + "/" + name + ".png", both);
}

/// CPU time of the calling thread, ms (the machine may be busy).
double ThreadCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

struct Count {
  int right = 0, wrong = 0, unread = 0;
};

// The misread rate each lead threshold of reading/decision.hpp leaves, estimated from the tail of
// the wrong winners' leads (lead_tail.hpp), and the leads that would leave 1e-5, 1e-6 and 1e-7.
// Shares are of all readings: a class's own share is larger by all readings / its readings.
void PrintLeadTails(const std::vector<double>& fit, const std::vector<double>& narrow_fit,
                    const std::vector<double>& misfit, std::size_t readings) {
  constexpr double kTailFrom = 4;  // past the bulk of wrong winners, below where they thin out
  std::printf(
      "wrong winners passing every check but the lead, of %zu readings "
      "(independent units; tail above %.0f):\n",
      readings, kTailFrom);
  const auto print = [&](const char* what, const std::vector<double>& leads, double threshold) {
    const LeadTail tail = FitLeadTail(leads, readings, kTailFrom);
    const double largest = leads.empty() ? 0 : *std::max_element(leads.begin(), leads.end());
    std::printf(
        "  %-19s %4zu, largest %5.1f, %3zu in the tail, scale %5.2f: misread share at "
        "%.0f %.1e; lead for 1e-5 %.1f, 1e-6 %.1f, 1e-7 %.1f\n",
        what, leads.size(), largest, tail.above, tail.scale, threshold, tail.rateAbove(threshold),
        tail.leadFor(1e-5), tail.leadFor(1e-6), tail.leadFor(1e-7));
  };
  print("fitting, narrow", narrow_fit, reading::kMinIndependentLeadOfANarrowFit);
  print("fitting, not narrow", fit, reading::kMinIndependentLeadOfAFit);
  print("not fitting", misfit, reading::kMinIndependentLead);
}

int Main(int argc, char** argv) {
  Args args;
  args.sweep.world = scene::World::kTuning;  // what tuning may look at
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
      args.sweep.world = WorldOrExit("pintag_reader_probe", next());
    } else if (a == "--seed") {
      args.sweep.seed = SeedOrExit("pintag_reader_probe", next());
    } else if (a == "--frames-per-bin") {
      args.sweep.frames_per_bin =
          IntegerOrExit("pintag_reader_probe", "--frames-per-bin", next(), 1, 100000);
    } else if (a == "--jitter") {
      args.jitter_px = NumberOrExit("pintag_reader_probe", "--jitter", next(), 0, 10);
    } else if (a == "--draws") {
      args.draws = IntegerOrExit("pintag_reader_probe", "--draws", next(), 1, 100000);
    } else if (a == "--threads") {
      args.threads = IntegerOrExit("pintag_reader_probe", "--threads", next(), 0, 1024);
    } else if (a == "--reader") {
      const std::string reader = next();
      if (reader != "model") {
        std::fprintf(stderr,
                     "pintag_reader_probe: --reader takes model (without it: the direct "
                     "reader), got \"%s\"\n",
                     reader.c_str());
        std::exit(2);
      }
      args.model = true;
    } else if (a == "--residuals") {
      args.residuals = next();
    } else if (a == "--csv") {
      args.csv = next();
    } else if (a == "--verbose") {
      args.verbose = true;
    } else if (a == "--max-size") {
      args.max_size_px = IntegerOrExit("pintag_reader_probe", "--max-size", next(), 1, 10000);
    } else if (a == "--frame") {
      args.frame = IntegerOrExit("pintag_reader_probe", "--frame", next(), 0, 10'000'000);
    } else if (a == "--jpeg-quality") {
      // As pintag_bench's: every frame saved at this quality, not the one its light draws.
      args.sweep.jpeg_quality =
          IntegerOrExit("pintag_reader_probe", "--jpeg-quality", next(), 1, 100);
    } else if (a == "--s-curve") {
      args.sweep.s_curve = true;  // as pintag_bench's
    } else if (a == "--vng-demosaic") {
      args.sweep.vng_demosaic = true;  // as pintag_bench's
    } else if (a == "--no-mosaic") {
      args.sweep.no_mosaic = true;  // as pintag_bench's: analysis of the held-out phone
    } else if (a == "--sensor-scale") {
      args.sweep.sensor_scale = IntegerOrExit("pintag_reader_probe", "--sensor-scale", next(), 1,
                                              4);  // as pintag_bench's
    } else {
      std::fprintf(stderr,
                   "usage: pintag_reader_probe [--world tuning|held-out] [--seed N] "
                   "[--frames-per-bin N] [--jitter PX --draws N] [--max-size PX] [--frame N] "
                   "[--jpeg-quality N] [--s-curve] [--vng-demosaic] [--no-mosaic] "
                   "[--sensor-scale K] [--threads N] "
                   "[--verbose] [--reader model [--csv FILE] [--residuals DIR]]\n");
      return a == "--help" ? 0 : 2;
    }
  }
  for (const std::string& error :
       {SweepOptionsError(args.sweep), TuningToolOptionsError(args.sweep)}) {
    if (!error.empty()) {
      std::fprintf(stderr, "pintag_reader_probe: %s\n", error.c_str());
      return 2;
    }
  }
  const scene::Camera camera = CameraFor(args.sweep.world);
  std::vector<FrameSpec> frames = MakeSweep(args.sweep, camera);
  std::erase_if(frames, [&](const FrameSpec& f) {
    return f.tagless() || kSizesPx[f.size_index] > args.max_size_px ||
           (args.frame >= 0 && f.index != args.frame);
  });
  // [hard][size][tilt]
  const auto slot = [](int hard, int size_index, int tilt_index) {
    return (static_cast<std::size_t>(hard) * kSizeCount + static_cast<std::size_t>(size_index)) *
               kTiltCount +
           static_cast<std::size_t>(tilt_index);
  };
  std::vector<Count> counts(slot(2, 0, 0));
  const auto at = [&](const FrameSpec& f) -> Count& {
    return counts[slot(f.hard ? 1 : 0, f.size_index, f.tilt_index)];
  };
  std::mutex mutex;
  // Independent leads of the wrong winners that pass every check but the lead, by which of the
  // three thresholds of reading/decision.hpp applies: fitting (excess at most kMaxExcess) on a
  // narrow square, fitting elsewhere, or not fitting. On a narrow square every check but the lead
  // already asks an excess of at most kMaxNarrowExcess, so no narrow winner counts as not fitting.
  std::vector<double> wrong_fit_leads, wrong_narrow_fit_leads, wrong_misfit_leads;
  std::size_t model_readings = 0;
  FILE* csv = args.csv.empty() ? nullptr : std::fopen(args.csv.c_str(), "w");
  if (!args.csv.empty() && csv == nullptr) {  // the run went on and wrote nothing
    std::fprintf(stderr, "pintag_reader_probe: cannot write %s\n", args.csv.c_str());
    return 2;
  }
  if (csv != nullptr) {
    std::fprintf(
        csv,
        "frame,size_px,tilt_deg,hard,draw,truth,key,winner,lead,excess,distance,"
        "luma_noise,chroma_noise,major,minor,sharpen,chroma_sigma,corner_error,corner_shift,"
        "evaluations,ms,residual,free_residual,luma_samples,chroma_samples,refused,"
        "chroma_correlation_x,chroma_correlation_y,lead_independent,others_pass,other_refusal,"
        "truth_over_winner,short_extent_px,chroma_deficit\n");
  }
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
        std::optional<TagKey> key;
        if (args.model) {
          const double t0 = ThreadCpuMs();
          reading::FittedModel fitted;
          const reading::ModelReading m =
              reading::ReadThroughModel(s.bgr, ChromaUpsampling::kBoth, quad, &fitted);
          const double ms = ThreadCpuMs() - t0;
          // The truth's own residual over the winner's: below 0 the search missed a codeword that
          // explains the samples better; above, the model prefers a wrong one.
          double truth_over_winner = std::numeric_limits<double>::quiet_NaN();
          if (fitted.fit.ok && m.decision.winner) {
            const reading::PaletteModel palette(fitted.luma, fitted.chroma, fitted.weights);
            double best = std::numeric_limits<double>::infinity();
            for (int turns = 0; turns < 4; ++turns) {
              double residual = 0;
              palette.fit(reading::CodewordLabels(truth.id, turns), &residual);
              best = std::min(best, residual);
            }
            truth_over_winner = best - m.decision.residual;
          }
          double corner_error = 0;
          for (std::size_t k = 0; k < 4; ++k) {
            corner_error += cv::norm(m.fit.corners[k] - truth.corners_px[k]) / 4;
          }
          const auto& dec = m.decision;
          std::string refused = reading::RefuseCodeword(m);
          // What the other checks say, the lead aside: what the lead rule is set from.
          reading::ModelReading any_lead = m;
          any_lead.decision.lead = 1e300;
          std::string other_refusal = reading::RefuseCodeword(any_lead);
          const bool others_pass = other_refusal.empty();
          std::replace(other_refusal.begin(), other_refusal.end(), ',', ';');
          std::replace(refused.begin(), refused.end(), ',', ';');
          if (!args.residuals.empty() && m.fit.ok) {
            char name[128];
            std::snprintf(name, sizeof name, "f%05d-%dpx-%ddeg-%s-d%d-%s", f.index,
                          kSizesPx[f.size_index], kTiltsDeg[f.tilt_index], f.hard ? "hard" : "mod",
                          d,
                          !dec.winner                       ? "none"
                          : dec.winner->value() == truth.id ? "right"
                                                            : "wrong");
            WriteResidual(args.residuals, name, s.bgr, m.fit);
          }
          const double short_extent =
              m.fit.ok
                  ? stage::ShortExtentPx(stage::HomographyFromQuad(
                        {m.fit.corners[0], m.fit.corners[1], m.fit.corners[2], m.fit.corners[3]}))
                  : 0;
          const bool narrow = m.fit.ok && reading::IsNarrow(m.fit.corners);
          // As the rules count it (reading::CountedLead: under the luminance noise floor, less
          // than the lead column).
          const double lead_independent =
              reading::CountedLead(m) / reading::VarianceInflation(m.fit.chroma_correlation);
          // Until the decision rule is settled, the probe accepts no codeword: it logs them.
          const std::lock_guard lock(mutex);
          if (csv != nullptr) {
            std::fprintf(csv,
                         "%d,%d,%d,%d,%d,%d,%d,%d,%.2f,%.2f,%d,%.5f,%.5f,%.2f,%.2f,%.2f,%.2f,%.3f,"
                         "%.3f,%d,%.2f,%.1f,%.1f,%zu,%zu,%s,%.4f,%.4f,%.2f,%d,%s,%.2f,%.2f,%.2f\n",
                         f.index, kSizesPx[f.size_index], kTiltsDeg[f.tilt_index], f.hard ? 1 : 0,
                         d, truth.id, refused.empty() ? dec.winner->value() : -1,
                         dec.winner ? dec.winner->value() : -1, dec.lead, dec.excess,
                         dec.runner_up_distance, m.fit.luma_noise, m.fit.chroma_noise,
                         m.fit.luma_blur.major, m.fit.luma_blur.minor, m.fit.luma_blur.sharpen,
                         m.fit.chroma_blur.sigma, corner_error, m.fit.corner_shift,
                         m.fit.evaluations, ms, dec.residual, dec.free_residual, m.fit.luma_samples,
                         m.fit.chroma_samples,
                         refused.empty() ? "" : refused.substr(0, refused.find(' ', 12)).c_str(),
                         m.fit.chroma_correlation.x, m.fit.chroma_correlation.y, lead_independent,
                         others_pass ? 1 : 0, other_refusal.c_str(), truth_over_winner,
                         short_extent, dec.chroma_deficit);
          }
          ++model_readings;
          if (dec.winner && dec.winner->value() != truth.id && others_pass) {
            if (!(dec.excess <= reading::kMaxExcess)) {  // as RefuseCodeword decides "fits"
              wrong_misfit_leads.push_back(lead_independent);
            } else {
              (narrow ? wrong_narrow_fit_leads : wrong_fit_leads).push_back(lead_independent);
            }
          }
          Count& c = at(f);
          if (!dec.winner) {
            ++c.unread;
          } else if (dec.winner->value() == truth.id) {
            ++c.right;
          } else {
            ++c.wrong;
          }
          continue;
        }
        const stage::CandidateReading r =
            stage::ReadCandidate(s.bgr, ChromaUpsampling::kBoth, quad, {});
        const std::lock_guard lock(mutex);
        Count& c = at(f);
        if (!r.reading.payload.key) {
          ++c.unread;
          if (args.verbose) {
            std::printf("unread f%d %dpx %ddeg %s truth %d: %s\n", f.index, kSizesPx[f.size_index],
                        kTiltsDeg[f.tilt_index], f.hard ? "hard" : "mod", truth.id,
                        r.reading.payload.error.c_str());
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
  if (csv != nullptr) std::fclose(csv);

  std::printf(
      "%s world, seed %llu, %d frames per bin, jitter %.2f px x %d: right / wrong / unread\n",
      ToString(args.sweep.world).c_str(), static_cast<unsigned long long>(args.sweep.seed),
      args.sweep.frames_per_bin, args.jitter_px, args.jitter_px > 0 ? args.draws : 1);
  if (args.sweep.jpeg_quality > 0) {
    std::printf("every frame at JPEG quality %d, not the quality its light draws\n",
                args.sweep.jpeg_quality);
  }
  if (args.sweep.s_curve) std::printf("every frame's phone with an S-shaped tone curve\n");
  if (args.sweep.vng_demosaic) {
    std::printf("every frame's phone with a colour filter array, demosaiced by VNG\n");
  }
  for (int hard = 0; hard < 2; ++hard) {
    std::printf("%s\n  size  ", hard ? "hard" : "moderate");
    for (int t = 0; t < kTiltCount; ++t) std::printf("%9d°", kTiltsDeg[t]);
    std::printf("   | <=72° right/all  wrong\n");
    for (int s = 0; s < kSizeCount; ++s) {
      if (kSizesPx[s] > args.max_size_px) continue;
      std::printf("  %3dpx ", kSizesPx[s]);
      int right = 0, all = 0, wrong = 0;
      for (int t = 0; t < kTiltCount; ++t) {
        const Count& c = counts[slot(hard, s, t)];
        std::printf(" %3d/%-2d/%-2d", c.right, c.wrong, c.unread);
        if (kTiltsDeg[t] <= 72) {
          right += c.right, all += c.right + c.wrong + c.unread, wrong += c.wrong;
        }
      }
      std::printf("   | %4d/%-4d %5d\n", right, all, wrong);
    }
  }
  if (args.model) {
    PrintLeadTails(wrong_fit_leads, wrong_narrow_fit_leads, wrong_misfit_leads, model_readings);
  }
  return 0;
}

}  // namespace
}  // namespace pintag::bench

int main(int argc, char** argv) {
  return pintag::bench::Main(argc, argv);
}
