#pragma once
// Stage 5e, corners fitted through the blur model. The square's edge fit (RefineCorners) puts an
// edge where a blurred step crosses its midpoint; on a small, blurred or strongly tilted tag the
// elements and the quiet zone's own blur pull that crossing, and corners a pixel off are common
// (benchmark: 48 px at 20° under hard light, 1.8 px). Cells of 3 px do not survive that. Here the
// corners move instead to where the blur model, with the blur already fitted, explains the pixels
// best. It runs only on candidates no reader decoded: it costs about a hundred model solves.
#include <opencv2/core.hpp>

#include "blur_model.hpp"
#include "quads.hpp"

namespace pintag::stage {

/// Largest distance (px) a corner may move from where the edge fit put it: further, the search
/// has found some other square.
inline constexpr double kCornerFitMaxMovePx = 2.5;

/// Largest mean square side (px) the search runs on: larger tags have cells wide enough for the
/// edge fit's corners, and each model solve costs in proportion to the tag's area.
inline constexpr double kCornerFitMaxSidePx = 64;

struct CornerFit {
  bool moved = false;  ///< the corners changed (else `quad` is the input)
  Quad quad{};
  double residual_before = 0;  ///< ResidualAtFittedBlur at the input corners
  double residual_after = 0;
  int evaluations = 0;
};

/// A pattern search over the eight corner coordinates, in steps of 0.4, 0.2 and 0.1 px, each
/// step kept only when it lowers the model's residual. Squares above kCornerFitMaxSidePx are
/// returned unmoved.
CornerFit FitCornersThroughBlur(const cv::Mat& bgr, const Quad& quad, const BlurFit& fit);

}  // namespace pintag::stage
