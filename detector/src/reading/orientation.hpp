#pragma once
// Stage 6a, orientation: which element is C0, and the tag's own b* levels for 0 and 1.
//
// The outer red quadrants are known bits: 0 on C0, 1 on the other three. For each of the four
// possible C0 the 3 supposed zeros must all lie clearly below the 9 supposed ones; exactly one
// choice may pass. Its two levels give the threshold (their midpoint) and the scale of each bit's
// margin. When C0 itself is hidden, the 9 ones must agree and the 0 level is taken from the
// darkest cell read. Bits too close to the threshold, or cells of the wrong colour (covered, or
// not a tag), are unknown: the codec decides what is missing, nothing is guessed here.

#include <string>

#include "pintag/codec/cells.hpp"
#include "pintag/detector/detection.hpp"
#include "reading/sampling.hpp"

namespace pintag::stage {

struct BitThresholds {
  double min_span_b = 20;        ///< least b* distance between the 1 and 0 levels
  double min_margin = 0.30;      ///< |margin| below this reads unknown
  double red_cell_min_a = 15;    ///< a red cell with a* below this is not red: unknown
  double green_cell_max_a = -5;  ///< a green cell with a* above this is not green: unknown
};

struct OrientationResult {
  bool ok = false;
  std::string error;
  int quarter_turns = 0;  ///< element `quarter_turns` of the sampled frame is C0
  double one_level = 0;   ///< b*
  double zero_level = 0;  ///< b*
  CellReading reading;    ///< canonical orientation
  BitMargins margins;     ///< canonical orientation
  int unknown = 0;
  double min_known_margin = 1e9;
};

/// Cells of `cells` as seen with element `quarter_turns` taken as element 0 (same rule as the
/// codec's RotateReading).
template <typename T>
BasicCells<T> RotateCells(const BasicCells<T>& cells, int quarter_turns) {
  const int r = ((quarter_turns % 4) + 4) % 4;
  BasicCells<T> out;
  for (int e = 0; e < kElements; ++e) {
    const int from = (e + r) % kElements;
    for (int s = 0; s < kGreenSectors; ++s) out.green[e][s] = cells.green[from][(s + 2 * r) % 8];
    for (int q = 0; q < kRedQuadrants; ++q) out.red[e][q] = cells.red[from][(q + r) % 4];
  }
  return out;
}

OrientationResult ReadOrientation(const CellSamples& samples, const BitThresholds& thresholds);

}  // namespace pintag::stage
