#pragma once
// Scoring one detector's output on one frame against the scene's truth, and the per-marker
// tallies the report is made of.

#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "detectors.hpp"
#include "sweep.hpp"

namespace pintag::bench {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// One detector on one frame.
struct Outcome {
  bool counted = false;                 ///< a tag was rendered fully visible: counts towards recall
  bool found = false;                   ///< a detection with the right id lies on the tag
  int misreads = 0;                     ///< tagged frame: detections on the tag with a wrong id
  int off_tag = 0;                      ///< tagged frame: detections away from the tag, any id
  int false_positives = 0;              ///< tagless frame: every detection
  double corner_error_px = kNaN;        ///< mean over the 4 corners of |detected − truth|
  double rotation_error_deg = kNaN;     ///< angle of R_detected · R_truthᵀ
  double translation_error_pct = kNaN;  ///< |t_detected − t_truth| / |t_truth| × 100
};

/// `truth` is empty on a tagless frame. A detection belongs to a tag when its centre lies within
/// 0.3 of the tag's projected side of the tag's centre.
Outcome Score(const FrameSpec& frame, const std::vector<scene::MarkerTruth>& truth,
              const std::vector<Found>& found);

struct Tally {
  int tags = 0;
  int found = 0;
  void add(const Tally& other) {
    tags += other.tags;
    found += other.found;
  }
  double percent() const { return tags > 0 ? 100.0 * found / tags : kNaN; }
};

/// One counted tag and whether the detector found it: the pairing of detectors pose by pose.
struct PoseOutcome {
  int frame = 0;  ///< FrameSpec::index, the same pose for every marker
  bool hard = false;
  int size_index = 0;
  int tilt_index = 0;
  bool found = false;
};

/// Everything the report says about one detector.
struct MarkerStats {
  std::string name;
  std::string description;
  Marker marker = Marker::kPinTag;
  /// [hard][size][tilt]
  std::array<std::array<std::array<Tally, kTiltCount>, kSizeCount>, 2> grid{};
  std::vector<PoseOutcome> poses;  ///< every counted tag, in the order scored
  int tagged_frames = 0;
  int excluded = 0;  ///< tags not fully visible (not counted)
  int misreads = 0;  ///< on the tag, wrong id
  int off_tag = 0;   ///< on a tagged frame, away from its tag
  int tagless_frames = 0;
  int false_positives = 0;
  int false_positive_frames = 0;
  std::array<std::vector<double>, kSizeCount> corner_error_px;
  std::vector<double> rotation_error_deg;
  std::vector<double> translation_error_pct;
  std::vector<double> time_ms_one_thread;
  std::vector<double> cpu_ms_one_thread;  ///< the calling thread's CPU time (load-proof)
  std::vector<double> time_ms_all_cores;
  std::vector<std::string> stage_names;
  std::vector<std::vector<double>> stage_ms;  ///< [stage][frame], one thread
  /// PinTag only: tags missed, by the stage that lost them (ExplainMiss), [hard][size].
  std::map<std::string, std::array<std::array<int, kSizeCount>, 2>> misses;

  void add(const FrameSpec& frame, const Outcome& outcome);
  /// hard: 0 moderate, 1 hard, −1 both; size / tilt −1 = all.
  Tally recall(int hard, int size_index, int tilt_index) const;
  std::vector<double> allCornerErrors() const;
};

/// Percentile (0 … 100) by linear interpolation; NaN when empty.
double Percentile(std::vector<double> values, double percent);
/// The arithmetic mean; NaN when empty.
double Mean(const std::vector<double>& values);
inline double Median(const std::vector<double>& values) {
  return Percentile(values, 50);
}

}  // namespace pintag::bench
