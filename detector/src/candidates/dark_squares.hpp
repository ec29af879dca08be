#pragma once
// Stage 3e, candidates found by their dark square alone. On a small tag under blur, JPEG chroma
// and a colour cast the red disks can lose all their red (a* below even the faint pass's
// threshold) while the tag still reads: the readers work from the fitted colours of all 48
// cells, not from red blobs. Such a tag is still, in min(R, G, B), one dark square in its white
// quiet zone (every printed colour has one low channel), and in max(R, G, B) four bright
// elements around a black centre. Here squares are looked for at half resolution by a local
// threshold and their contours, kept only when they are four-sided and convex and show that
// pattern, and returned with their corners refined at full resolution.

#include <functional>
#include <opencv2/core.hpp>
#include <vector>

#include "candidates/quads.hpp"

namespace pintag::stage {

struct DarkSquareLimits {
  /// Largest bounding-box side (full-resolution px) looked for: larger tags keep enough red for
  /// the red passes, and the half-resolution window would see only their inside.
  double max_side_px = 80;
  /// FindQuads' size scale N (DetectorOptions::min_square_px); outlines whose bounding box is
  /// under N / 2 are not looked at.
  double min_square_px = 20;
};

/// Whether, in max(R, G, B), each of the four elements of `quad` (corners clockwise) is brighter
/// than the square's centre by a margin (3 × 3 px means). Squares found here meet it on their
/// outline and a stricter test on their refined corners (the margins beside the elements dark
/// too); corners moved later (the corner fit) must meet it again. The stricter test is not asked
/// there: on a blurred 32 px tag whose fitted corners were within a few tenths of a pixel of the
/// truth, the 2.5 px margins had taken up the white of the quiet zone.
bool ElementsOutshineCentre(const cv::Mat& bgr, const Quad& quad);

/// Squares in `bgr` whose half-resolution min(R, G, B) image is `dark_half` (FrameScan), skipping
/// any whose rough or refined centre `skip` accepts (a tag decoded already). Corners clockwise on
/// screen, refined (RefineCorners), full-resolution px.
std::vector<Quad> FindDarkSquares(const cv::Mat& bgr, const cv::Mat& dark_half,
                                  const DarkSquareLimits& limits,
                                  const std::function<bool(cv::Point2d)>& skip);

}  // namespace pintag::stage
