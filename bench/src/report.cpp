#include "report.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "plot.hpp"
#include "recall_comparison.hpp"

namespace pintag::bench {
namespace {

std::string Fmt(const char* format, double v) {
  if (std::isnan(v)) return "–";
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

// One decimal with its sign, the minus typeset (−) as the hand-written text has it.
std::string Signed(double v) {
  std::string text = Fmt("%+.1f", v);
  if (!text.empty() && text[0] == '-') text.replace(0, 1, "−");
  return text;
}

std::string Percent(const Tally& t) {
  return t.tags > 0 ? Fmt("%.1f", t.percent()) : "–";
}

// "all (moderate / hard)"
std::string RecallCell(const MarkerStats& m, int size_index, int tilt_index) {
  return Percent(m.recall(-1, size_index, tilt_index)) + " (" +
         Percent(m.recall(0, size_index, tilt_index)) + " / " +
         Percent(m.recall(1, size_index, tilt_index)) + ")";
}

// The target region of issue 6: tags of at least 24 px, tilted at most 72°.
bool InTarget(int size_index, int tilt_index) {
  return kSizesPx[size_index] >= 24 && kTiltsDeg[tilt_index] <= 72;
}

Tally TargetRecall(const MarkerStats& m) {
  Tally t;
  for (int s = 0; s < kSizeCount; ++s) {
    for (int a = 0; a < kTiltCount; ++a) {
      if (InTarget(s, a)) t.add(m.recall(-1, s, a));
    }
  }
  return t;
}

std::string Ratio(double a, double b) {
  if (std::isnan(a) || std::isnan(b) || b <= 0) return "–";
  return Fmt("%.2f", a / b) + " ×";
}

std::string Header(const std::vector<std::string>& cells) {
  std::string line = "|", rule = "|";
  for (std::size_t i = 0; i < cells.size(); ++i) {
    line += " " + cells[i] + " |";
    rule += i == 0 ? "---|" : "--:|";
  }
  return line + "\n" + rule + "\n";
}

std::string Row(const std::vector<std::string>& cells) {
  std::string line = "|";
  for (const std::string& c : cells) line += " " + c + " |";
  return line + "\n";
}

// Issue 19 allows PinTag to trail ArUco in at most this many target bins.
constexpr std::size_t kBinsBehindAllowed = 2;

// How far PinTag's target-bin recall is from `other`'s beyond chance: the bins a detector as good
// as `other` would trail in, and the paired difference over the same poses, per light.
void WriteRecallComparison(const MarkerStats& pintag, const MarkerStats& other, int bins_behind,
                           std::ostringstream& md) {
  std::vector<BinTally> bins;
  for (int si = 0; si < kSizeCount; ++si) {
    for (int ti = 0; ti < kTiltCount; ++ti) {
      if (!InTarget(si, ti)) continue;
      const Tally t = other.recall(-1, si, ti);
      bins.push_back({t.tags, t.found});
    }
  }
  const auto chance_sentence = [&](const BinsBehindByChance& chance) {
    const double at_least_observed =
        bins_behind > 0 ? 1 - chance.atMost(static_cast<std::size_t>(bins_behind) - 1) : 1.0;
    return Fmt("%.1f", chance.expected) + " of these bins on average, in at most " +
           std::to_string(kBinsBehindAllowed) + " of them in " +
           Fmt("%.0f", 100 * chance.atMost(kBinsBehindAllowed)) +
           " % of sweeps this size, and in " + std::to_string(bins_behind) + " or more in " +
           Fmt("%.1f", 100 * at_least_observed) + " %";
  };
  md << "\nA detector exactly as good as " << other.name
     << " in every bin, missing tags independently of it, would find fewer than it in "
     << chance_sentence(ChanceOfBinsBehind(bins, BinRate::kObserved))
     << ", taking each bin's rate as " << other.name
     << "'s found / tags; that rate makes a bin it found whole one no detector can trail in. "
        "With (found + ½) / (tags + 1) instead: "
     << chance_sentence(ChanceOfBinsBehind(bins, BinRate::kSmoothed))
     << ". On the same poses misses go together, which makes trailing rarer than either says. "
        "The count of bins behind moves this much with the estimate; the paired test is the "
        "measure. Paired over the same poses (target bins; the interval is the normal 95 % one, p "
        "is McNemar's exact two-sided test of equal recall):\n\n";
  md << Header({"light", "poses", "PinTag only", other.name + " only",
                "PinTag − " + other.name + ", points (95 % interval)", "p"});
  std::map<int, bool> other_found;
  for (const PoseOutcome& pose : other.poses) {
    if (InTarget(pose.size_index, pose.tilt_index)) other_found[pose.frame] = pose.found;
  }
  for (int light = 0; light <= 2; ++light) {  // moderate, hard, both
    PairedOutcomes paired;
    for (const PoseOutcome& pose : pintag.poses) {
      if (!InTarget(pose.size_index, pose.tilt_index)) continue;
      if (light < 2 && pose.hard != (light == 1)) continue;
      const auto it = other_found.find(pose.frame);
      if (it == other_found.end()) continue;  // counted for one marker only
      int& cell = pose.found ? (it->second ? paired.both : paired.only_first)
                             : (it->second ? paired.only_second : paired.neither);
      ++cell;
    }
    const RecallDifference difference = CompareRecall(paired);
    md << Row({light == 0   ? "moderate"
               : light == 1 ? "hard"
                            : "both",
               std::to_string(paired.poses()), std::to_string(paired.only_first),
               std::to_string(paired.only_second),
               Signed(difference.points) + " (" + Signed(difference.low) + " to " +
                   Signed(difference.high) + ")",
               Fmt(difference.p_value < 0.001 ? "%.1e" : "%.3f", difference.p_value)});
  }
}

/// What a world's numbers are worth, for the report's first table.
const char* WorldRole(scene::World world) {
  switch (world) {
    case scene::World::kTuning:
      return "the side the detector is tuned on: not evidence";
    case scene::World::kHeldOut:
      return "backgrounds, seeds, camera and rendering path the tuning world does not use; a "
             "validation set, not a blind one (docs/BENCHMARKS.md, \"How held out the held-out "
             "world is\")";
    case scene::World::kBlind:
      return "the held-out world's rendering path and phone on photographs, a camera and seeds of "
             "its own, run whole when an issue about the detector ends: no decision has looked at "
             "it before";
  }
  return "?";
}

}  // namespace

std::string ReportMarkdown(const BenchResult& r) {
  std::ostringstream md;
  const MachineInfo& m = r.machine;
  const MarkerStats& pintag = r.markers.at(0);
  md << "## Results\n\n";
  const SweepOptions headline;
  const bool headline_size = r.sweep.frames_per_bin == headline.frames_per_bin &&
                             r.sweep.tagless_frames == headline.tagless_frames;
  const char* kind = r.chosen_frames_only ? "**frames chosen with --frame**, not a sweep"
                     : r.sweep.quick      ? "**quick mode**: too few frames for conclusions"
                     : headline_size      ? "full sweep"
                                          : "a sweep of its own size, below";
  md << "Generated by `pintag_bench` (" << kind << ") — `" << r.command_line << "`.\n\n";
  md << "| | |\n|---|---|\n";
  md << "| world | **" << ToString(r.sweep.world) << "** (" << WorldRole(r.sweep.world) << ") |\n";
  if (r.sweep.jpeg_quality > 0) {
    md << "| JPEG quality | **every frame at " << r.sweep.jpeg_quality
       << "** (`--jpeg-quality`), not the quality its light draws |\n";
  }
  if (r.sweep.s_curve) {
    md << "| tone curve | **an S-curve on every frame** (`--s-curve`), as well as the power its "
          "light draws |\n";
  }
  if (r.sweep.vng_demosaic) {
    md << "| sensor | **a colour filter array on every frame, demosaiced by variable numbers of "
          "gradients** (`--vng-demosaic`), not bilinearly |\n";
  }
  if (r.sweep.no_mosaic) {
    md << "| sensor | **no colour filter array** (`--no-mosaic`): every pixel senses all three "
          "colours, nothing is demosaiced |\n";
  }
  if (r.sweep.sensor_scale > 1) {
    md << "| sensor | **" << r.sweep.sensor_scale
       << " × the output's resolution** each way (`--sensor-scale`), demosaiced there and scaled "
          "down |\n";
  }
  if (r.sweep.jpeg_full_chroma) {
    md << "| JPEG colour | **full resolution (4:4:4)** (`--jpeg-chroma 444`), not the 4:2:0 "
          "phones save |\n";
  }
  md << "| date | " << m.date_utc << " |\n";
  md << "| commit | " << m.commit << " |\n";
  md << "| CPU | " << m.cpu_model << ", " << m.cores << " logical cores |\n";
  md << "| load average (1, 5, 15 min) | before " << m.load_start << "; after " << m.load_end
     << " |\n";
  md << "| build | " << m.compiler << "; OpenCV " << m.opencv << "; libapriltag " << m.apriltag
     << " |\n";
  md << "| image | " << r.camera.width << " × " << r.camera.height
     << " BGR, pinhole fx = fy = " << r.camera.fx
     << " px, no distortion; one 50 mm tag per tagged frame |\n";
  md << "| threads | pass 1: one thread (cv::setNumThreads(1), apriltag nthreads 1, PinTag "
        "threads 1)";
  if (r.all_cores > 0) {
    md << "; pass 2: all " << r.all_cores << " cores (the same three settings = " << r.all_cores
       << "), timed on " << r.floor_ms_all_cores.size() << " of the "
       << r.floor_ms_one_thread.size() << " frames (one chunk of 24 frames in "
       << (r.sweep.quick ? 1 : r.all_cores_every) << ")";
  }
  md << " |\n";
  md << "| frames | " << r.tagged_frames << " tagged poses (";
  if (r.chosen_frames_only) {
    md << "the frames named by --frame, of a sweep of ";
  }
  if (r.sweep.quick) {
    md << "1 per size × tilt bin, photometry alternating";
  } else {
    md << r.sweep.frames_per_bin << " per size × tilt × photometry bin, 7 × 7 × 2 bins";
  }
  int excluded = 0;
  for (const MarkerStats& s : r.markers) excluded = std::max(excluded, s.excluded);
  std::vector<std::string> drawn;  // the AprilTag detectors share one marker
  for (const MarkerStats& s : r.markers) {
    if (std::find(drawn.begin(), drawn.end(), ToString(s.marker)) == drawn.end()) {
      drawn.push_back(ToString(s.marker));
    }
  }
  std::string markers;
  for (const std::string& name : drawn) markers += (markers.empty() ? "" : ", ") + name;
  md << "), each rendered with each marker run (" << markers << "); " << r.tagless_frames
     << " tagless frames on " << r.photos << " photographs; " << excluded
     << " tags not fully visible, left out of recall |\n";
  md << "| wall time | " << Fmt("%.0f", r.wall_seconds) << " s (rendering included) |\n\n";

  // --- summary ---
  md << "### Accuracy\n\n";
  md << "Misreads: detections on a tag with another id. Off the tag: detections on a tagged "
        "frame away from its tag (in the background or the label's print), any id.\n\n";
  md << Header({"detector", "recall %", "recall % ≥24 px, ≤72°", "misreads", "off the tag",
                "tagless FP (frames)", "corner err. px", "rotation err. °", "translation err. %"});
  for (const MarkerStats& s : r.markers) {
    md << Row({"**" + s.name + "**", Percent(s.recall(-1, -1, -1)), Percent(TargetRecall(s)),
               std::to_string(s.misreads), std::to_string(s.off_tag),
               std::to_string(s.false_positives) + " (" + std::to_string(s.false_positive_frames) +
                   " of " + std::to_string(s.tagless_frames) + ")",
               Fmt("%.3f", Median(s.allCornerErrors())), Fmt("%.2f", Median(s.rotation_error_deg)),
               Fmt("%.2f", Median(s.translation_error_pct))});
  }
  const std::string all = r.all_cores > 0 ? std::to_string(r.all_cores) + " cores" : "all cores";
  md << "\n### Speed\n\nms per frame, over every frame of the sweep (tagged and tagless). Wall: "
        "elapsed time of the call; CPU: the calling thread's CPU time (with one thread all the "
        "work "
        "is in that thread; this is the column that other processes on the machine disturb least). "
        "A hub's throughput follows the mean; a scanner waits on the slowest frames (p99, "
        "max).\n\n";
  md << Header({"detector", "wall mean", "wall p90", "wall p99", "wall max", "CPU mean", "CPU p90",
                "CPU p99", "CPU max", all + " wall mean", all + " wall p99"});
  const auto timing_row = [&](const std::string& name, const std::vector<double>& wall,
                              const std::vector<double>& cpu, const std::vector<double>& cores) {
    return Row({name, Fmt("%.2f", Mean(wall)), Fmt("%.2f", Percentile(wall, 90)),
                Fmt("%.2f", Percentile(wall, 99)), Fmt("%.2f", Percentile(wall, 100)),
                Fmt("%.2f", Mean(cpu)), Fmt("%.2f", Percentile(cpu, 90)),
                Fmt("%.2f", Percentile(cpu, 99)), Fmt("%.2f", Percentile(cpu, 100)),
                Fmt("%.2f", Mean(cores)), Fmt("%.2f", Percentile(cores, 99))});
  };
  for (const MarkerStats& s : r.markers) {
    md << timing_row("**" + s.name + "**", s.time_ms_one_thread, s.cpu_ms_one_thread,
                     s.time_ms_all_cores);
  }
  md << timing_row("BGR→gray (floor)", r.floor_ms_one_thread, r.floor_cpu_ms_one_thread,
                   r.floor_ms_all_cores);
  md << "\nTime ratios, PinTag's statistic over the other's, 1 thread (below 1: PinTag is "
        "faster; the median only beside the others):\n\n";
  md << Header({"", "wall mean", "wall median", "wall p90", "wall p99", "wall max", "CPU mean",
                "CPU p99", all + " wall mean"});
  const auto ratio = [](const std::vector<double>& a, const std::vector<double>& b, double pct) {
    return pct < 0 ? Ratio(Mean(a), Mean(b)) : Ratio(Percentile(a, pct), Percentile(b, pct));
  };
  for (std::size_t i = 1; i < r.markers.size(); ++i) {
    const MarkerStats& s = r.markers[i];
    const auto& pw = pintag.time_ms_one_thread;
    const auto& pc = pintag.cpu_ms_one_thread;
    md << Row({"PinTag ÷ " + s.name, ratio(pw, s.time_ms_one_thread, -1),
               ratio(pw, s.time_ms_one_thread, 50), ratio(pw, s.time_ms_one_thread, 90),
               ratio(pw, s.time_ms_one_thread, 99), ratio(pw, s.time_ms_one_thread, 100),
               ratio(pc, s.cpu_ms_one_thread, -1), ratio(pc, s.cpu_ms_one_thread, 99),
               ratio(pintag.time_ms_all_cores, s.time_ms_all_cores, -1)});
  }
  md << "\n";

  // --- recall by size and by tilt ---
  std::vector<std::string> names{"square side px"};
  for (const MarkerStats& s : r.markers) names.push_back(s.name);
  md << "### Recall by size (all tilts)\n\n% of tags found with the right id: all (moderate / "
        "hard).\n\n";
  md << Header(names);
  for (int si = 0; si < kSizeCount; ++si) {
    std::vector<std::string> row{std::to_string(kSizesPx[si])};
    for (const MarkerStats& s : r.markers) row.push_back(RecallCell(s, si, -1));
    md << Row(row);
  }
  names[0] = "tilt °";
  md << "\n### Recall by tilt (all sizes)\n\n";
  md << Header(names);
  for (int ti = 0; ti < kTiltCount; ++ti) {
    std::vector<std::string> row{std::to_string(kTiltsDeg[ti])};
    for (const MarkerStats& s : r.markers) row.push_back(RecallCell(s, -1, ti));
    md << Row(row);
  }

  // --- the bins the next step is judged on ---
  const auto aruco_it = std::find_if(r.markers.begin(), r.markers.end(),
                                     [](const MarkerStats& s) { return s.name == "ArUco"; });
  if (aruco_it != r.markers.end()) {
    const MarkerStats& aruco = *aruco_it;
    md << "\n### Recall per size × tilt bin: PinTag / ArUco\n\n";
    md << "% found, both photometries (" << pintag.recall(-1, 0, 0).tags
       << " tags per bin). **Bold**: a bin of the target region (≥ 24 px, ≤ 72°) where PinTag "
          "finds fewer than ArUco.\n\n";
    std::vector<std::string> tilt_header{"side px \\ tilt °"};
    for (int t : kTiltsDeg) tilt_header.push_back(std::to_string(t));
    md << Header(tilt_header);
    int behind = 0, target_bins = 0;
    for (int si = 0; si < kSizeCount; ++si) {
      std::vector<std::string> row{std::to_string(kSizesPx[si])};
      for (int ti = 0; ti < kTiltCount; ++ti) {
        const Tally p = pintag.recall(-1, si, ti), a = aruco.recall(-1, si, ti);
        std::string cell = Fmt("%.0f", p.percent()) + " / " + Fmt("%.0f", a.percent());
        if (InTarget(si, ti)) {
          ++target_bins;
          if (p.found * std::max(1, a.tags) < a.found * std::max(1, p.tags)) {
            ++behind;
            cell.insert(0, "**");
            cell += "**";
          }
        }
        row.push_back(cell);
      }
      md << Row(row);
    }
    md << "\nPinTag finds fewer tags than ArUco in " << behind << " of the " << target_bins
       << " target bins.\n";
    WriteRecallComparison(pintag, aruco, behind, md);
  }

  // --- corner error by size ---
  names[0] = "square side px";
  md << "\n### Median corner error by size (px, tags found)\n\n";
  md << Header(names);
  for (int si = 0; si < kSizeCount; ++si) {
    std::vector<std::string> row{std::to_string(kSizesPx[si])};
    for (const MarkerStats& s : r.markers)
      row.push_back(Fmt("%.3f", Median(s.corner_error_px[si])));
    md << Row(row);
  }

  // --- where PinTag loses tags ---
  if (!pintag.misses.empty()) {
    md << "\n### Where PinTag loses tags\n\nEvery tag PinTag missed, by what the detector did "
          "with it (`bench/src/explain.cpp`): no candidate on the tag; a candidate refused, with "
          "its corners' distance from the truth and the detector's reason; or one decoded as "
          "another key; each beside what the direct reader makes of the tag on its true "
          "corners. Columns: square side px, all tilts, both photometries; then totals per "
          "photometry.\n\n";
    std::vector<std::string> header{"stage that lost the tag"};
    for (int px : kSizesPx) header.push_back(std::to_string(px));
    header.insert(header.end(), {"moderate", "hard", "all"});
    md << Header(header);
    std::array<int, kSizeCount> size_total{};
    int moderate_total = 0, hard_total = 0;
    for (const auto& [why, counts] : pintag.misses) {
      std::vector<std::string> row{why};
      int moderate = 0, hard = 0;
      for (int si = 0; si < kSizeCount; ++si) {
        const int n = counts[0][si] + counts[1][si];
        size_total[si] += n;
        moderate += counts[0][si];
        hard += counts[1][si];
        row.push_back(n ? std::to_string(n) : "");
      }
      moderate_total += moderate;
      hard_total += hard;
      row.insert(row.end(),
                 {std::to_string(moderate), std::to_string(hard), std::to_string(moderate + hard)});
      md << Row(row);
    }
    std::vector<std::string> row{"**missed**"};
    for (int n : size_total) row.push_back(std::to_string(n));
    row.insert(row.end(), {std::to_string(moderate_total), std::to_string(hard_total),
                           std::to_string(moderate_total + hard_total)});
    md << Row(row);
  }

  // --- PinTag's stages ---
  if (!pintag.stage_names.empty()) {
    md << "\n### PinTag time per stage (1 thread, `DetectResult::timings`, all frames)\n\n";
    md << Header(
        {"stage (DESIGN.md §3)", "mean ms", "p90 ms", "p99 ms", "max ms", "share of mean total"});
    double total_mean = 0;
    for (std::size_t i = 0; i < pintag.stage_names.size(); ++i) {
      if (pintag.stage_names[i] == "total") {
        for (double v : pintag.stage_ms[i]) total_mean += v;
        total_mean /= std::max<std::size_t>(1, pintag.stage_ms[i].size());
      }
    }
    for (std::size_t i = 0; i < pintag.stage_names.size(); ++i) {
      const std::vector<double>& v = pintag.stage_ms[i];
      double mean = 0;
      for (double x : v) mean += x;
      mean /= std::max<std::size_t>(1, v.size());
      md << Row({pintag.stage_names[i], Fmt("%.3f", mean), Fmt("%.3f", Percentile(v, 90)),
                 Fmt("%.3f", Percentile(v, 99)), Fmt("%.3f", Percentile(v, 100)),
                 total_mean > 0 ? Fmt("%.0f %%", 100 * mean / total_mean) : "–"});
    }
  }

  md << "\n### Plots\n\n";
  md << "![Recall vs tilt](images/bench-recall-vs-tilt.png)\n\n";
  md << "![Recall vs size](images/bench-recall-vs-size.png)\n";
  return md.str();
}

bool WriteReport(const BenchResult& r, const std::string& out_dir, std::string* error) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(fs::path(out_dir) / "images", ec);
  if (ec) {
    *error = "cannot create " + out_dir + "/images: " + ec.message();
    return false;
  }
  // Plots: one panel per photometry, one line per detector.
  const auto plot = [&](bool by_tilt, const std::string& file) {
    PlotSpec spec;
    spec.title = by_tilt ? "Recall vs tilt" : "Recall vs size";
    char sub[256];
    std::snprintf(sub, sizeof sub,
                  "%d × %d frames, tags found with the right id; %s; %d tagged poses%s",
                  r.camera.width, r.camera.height,
                  by_tilt ? "each point: all 7 sizes 14–160 px" : "each point: all 7 tilts 0–78°",
                  r.tagged_frames, r.sweep.quick ? " (quick mode)" : "");
    spec.subtitle = sub;
    spec.x_label = by_tilt ? "tilt (degrees from facing the camera)"
                           : "black-square side (px, facing the camera; log scale)";
    spec.log_x = !by_tilt;
    const int n = by_tilt ? kTiltCount : kSizeCount;
    for (int i = 0; i < n; ++i) spec.x.push_back(by_tilt ? kTiltsDeg[i] : kSizesPx[i]);
    for (int hard = 0; hard < 2; ++hard) {
      PlotPanel panel;
      panel.title = hard ? "hard photometry" : "moderate photometry";
      for (const MarkerStats& s : r.markers) {
        PlotSeries series{s.name, {}};
        for (int i = 0; i < n; ++i) {
          const Tally t = by_tilt ? s.recall(hard, -1, i) : s.recall(hard, i, -1);
          series.y.push_back(t.percent());
        }
        panel.series.push_back(std::move(series));
      }
      spec.panels.push_back(std::move(panel));
    }
    return WritePlot(spec, (fs::path(out_dir) / "images" / file).string(), error);
  };
  if (!plot(true, "bench-recall-vs-tilt.png") || !plot(false, "bench-recall-vs-size.png")) {
    return false;
  }

  const fs::path md_path = fs::path(out_dir) / "BENCHMARKS.md";
  const std::string generated =
      std::string(kBeginMarker) + "\n\n" + ReportMarkdown(r) + "\n" + kEndMarker + "\n";
  std::string text;
  if (std::ifstream in(md_path); in) {
    std::stringstream buf;
    buf << in.rdbuf();
    text = buf.str();
  }
  const std::size_t begin = text.find(kBeginMarker);
  const std::size_t end = text.find(kEndMarker);
  if (begin != std::string::npos && end != std::string::npos && end > begin) {
    std::size_t after = end + std::string(kEndMarker).size();
    if (after < text.size() && text[after] == '\n') ++after;
    text = text.substr(0, begin) + generated + text.substr(after);
  } else if (text.empty()) {
    text =
        "# Benchmarks\n\nHow to run the benchmark and what the columns mean: the project's "
        "docs/BENCHMARKS.md.\n\n" +
        generated;
  } else {
    text += "\n" + generated;
  }
  std::ofstream out(md_path);
  out << text;
  if (!out) {
    *error = "cannot write " + md_path.string();
    return false;
  }
  return true;
}

}  // namespace pintag::bench
