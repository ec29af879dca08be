#pragma once
// docs/BENCHMARKS.md and the plots from one run of the sweep.

#include <string>
#include <vector>

#include "machine.hpp"
#include "metrics.hpp"
#include "pintag/scene/scene.hpp"
#include "sweep.hpp"

namespace pintag::bench {

struct BenchResult {
  MachineInfo machine;
  SweepOptions sweep;
  scene::Camera camera;
  int tagged_frames = 0;
  int tagless_frames = 0;
  int photos = 0;                           ///< photographs available as backgrounds
  std::vector<MarkerStats> markers;         ///< PinTag first, then ArUco, then the AprilTags
  std::vector<double> floor_ms_one_thread;  ///< BGR->gray per frame
  std::vector<double> floor_ms_all_cores;
  std::vector<double> floor_cpu_ms_one_thread;
  int all_cores = 0;        ///< threads of the second pass; 0 = not run
  int all_cores_every = 1;  ///< the second pass timed every this-many-th chunk
  double wall_seconds = 0;
  bool chosen_frames_only = false;  ///< --frame: the frames named, not the sweep
  std::string command_line;
};

/// The generated part of BENCHMARKS.md (between the markers below).
std::string ReportMarkdown(const BenchResult& result);

inline constexpr const char* kBeginMarker = "<!-- pintag_bench: generated below -->";
inline constexpr const char* kEndMarker = "<!-- pintag_bench: generated above -->";

/// Writes `out_dir`/BENCHMARKS.md (replacing only the text between the markers when the file
/// exists with them; creating it otherwise) and `out_dir`/images/bench-recall-vs-tilt.png and
/// bench-recall-vs-size.png. False with `error` set on failure.
bool WriteReport(const BenchResult& result, const std::string& out_dir, std::string* error);

}  // namespace pintag::bench
