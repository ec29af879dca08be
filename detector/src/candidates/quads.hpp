#pragma once
// Stage 3a, quads: in a region around a blob cluster, the tag (black square with its elements) is
// one dark shape in min(R, G, B) — every printed colour has a low channel, the quiet zone has none
// — ringed by the white quiet zone. Otsu separates the two; dark contours with four corners are
// quads.

#include <array>
#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

namespace pintag::stage {

using Quad = std::array<cv::Point2d, 4>;  ///< clockwise on screen (x right, y down), px

/// min(R, G, B) of `pixels` interleaved BGR pixels (vectorised where the CPU allows).
void MinChannelRow(const std::uint8_t* bgr, std::ptrdiff_t pixels, std::uint8_t* out);
/// min(R, G, B) of `bgr` inside `roi` (CV_8U, roi-sized).
cv::Mat MinChannel(const cv::Mat& bgr, const cv::Rect& roi);

/// A 3 × 3 closing of `binary` (CV_8U), in place: what cv::morphologyEx(MORPH_CLOSE) with a 3 × 3
/// rectangle gives, pixels outside the image left out of both steps.
void CloseGaps3x3(cv::Mat& binary);

/// Quads in `dark` (MinChannel of the region at `origin`), returned in image coordinates.
/// `min_side_px`: shorter quads are dropped. When `anchors` (image coordinates) is given, only
/// contours whose bounding box holds at least `min_anchors_inside` of them are fitted (a tag
/// holds its red blobs; 2 for a pair of the faint pass),
/// which keeps textured photo regions cheap. `close_gaps` bridges gaps of one or two pixels in the
/// dark shape first (a cover can leave a thin band of black at the square's edge); without it, a
/// quiet zone two pixels wide still separates the tag from dark ground (a steeply tilted tag).
std::vector<Quad> FindQuads(const cv::Mat& dark, cv::Point origin, double min_side_px,
                            const std::vector<cv::Point2d>* anchors = nullptr,
                            bool close_gaps = true, int min_anchors_inside = 3);

/// Where a tag holding `anchors` (its red blobs, image coordinates) can lie: their bounding box
/// grown by 0.8 of the largest nearest-anchor distance (a square's edge is half an element
/// spacing beyond its element centres; the rest is for perspective), clipped to `within`.
cv::Rect AnchorsRegion(const std::vector<cv::Point2d>& anchors, const cv::Rect& within);

/// Twice the signed area; positive when clockwise on screen.
double SignedArea2(const Quad& quad);

/// The mean of the four sides, px.
double MeanSidePx(const Quad& quad);

/// Whether `p` lies inside `quad` or on its edge.
bool QuadContains(const Quad& quad, cv::Point2d p);

/// Whether `a` and `b` are one square: every corner within `tolerance_px` of the other's, whichever
/// corner each starts from.
bool SameSquare(const Quad& a, const Quad& b, double tolerance_px);

/// A convex four-cornered polygon approximating `hull` (a convex hull, integer px), tried at each
/// of `tolerances_px` in turn (the largest distance allowed between hull and polygon); corners
/// clockwise on screen. False when no tolerance gives one.
bool QuadFromHull(const std::vector<cv::Point>& hull, std::initializer_list<double> tolerances_px,
                  Quad* quad);

}  // namespace pintag::stage
