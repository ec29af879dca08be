#pragma once
// The last rule a model winner meets on a narrow square (stage 5c): two more reads from its fitted
// corners moved a little must choose it too. A wrong winner there owes its lead to how one read's
// corners and blur settled; from other corners the model usually prefers another codeword. It only
// refuses: RefuseCodeword's rules still decide everything else.

#include <cstdint>
#include <opencv2/core.hpp>

#include "pintag/codec/tag_key.hpp"
#include "pintag/detector/chroma_upsampling.hpp"
#include "reading/model_reader.hpp"

namespace pintag::reading {

/// How far (px) each corner is moved, in a fixed direction of its own, for each re-read: about
/// the corner error the reader probe's jitter of 0.6 px per axis gives (chosen on the tuning
/// probe in the fifteenth sitting, docs/DETECTOR-RESEARCH.md).
inline constexpr double kRereadShiftPx = 0.75;

/// Whether an accepted winner on a square with these fitted corners must be re-read: on a narrow
/// square (IsNarrow), whatever its lead.
bool NeedsRereading(const Corners& fitted);

/// `fitted` with each corner moved by kRereadShiftPx in a fixed direction of its own (`sign` +1
/// or -1: the two re-reads move them opposite ways). The directions are unrelated from corner to
/// corner, so the moved square differs in place, size, turn and perspective at once, as a
/// candidate's corner errors do.
Corners MovedCorners(const Corners& fitted, double sign);

/// One re-read: the model fitted from `start` and its codeword decided.
struct Reread {
  bool same_winner = false;  ///< a model was fitted, its square not too small, the same winner
  double fit_ms = 0;
  double codeword_ms = 0;
};
Reread ReadAgain(const cv::Mat& bgr, ChromaUpsampling upsampling, const Corners& start,
                 TagKey winner);

}  // namespace pintag::reading
