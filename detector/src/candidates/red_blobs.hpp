#pragma once
// Stage 2, red blobs: connected components of the redness mask, kept when their size fits an
// element and their shape is an ellipse (a disk seen at any angle).

#include <opencv2/core.hpp>
#include <vector>

#include "candidates/redness.hpp"

namespace pintag::stage {

struct RedBlob {
  cv::Point2d centroid;  ///< px
  int area = 0;          ///< px
  double major = 0;      ///< full axis lengths of the ellipse with the same second moments, px
  double minor = 0;
  double fill = 0;   ///< area / that ellipse's area; about 1 for a filled ellipse
  double angle = 0;  ///< direction of the major axis, radians (image x towards y)
  cv::Rect box;
};

struct BlobLimits {
  int min_area = 3;        ///< px
  int max_area = 1 << 20;  ///< px
  double min_fill = 0.55;
  double max_elongation = 8;  ///< major / minor (a disk tilted 80° is ~5.8)
  int max_blobs = 4000;       ///< keep the largest this many
};

/// 8-connected components of the runs, with their moments, filtered by `limits`.
std::vector<RedBlob> FindRedBlobs(const RedRuns& red, const BlobLimits& limits);
/// Whether the blob sits in a ring that is neither red nor white, as a tag's red disk sits in its
/// green ring: on an ellipse at 1.5, 2.5 or 3.5 times the blob's semi-axes (the larger ones for a
/// blurred disk whose red core is smaller than the disk), in 8 directions, at least 5 samples must
/// have a* < 10 and L* < 85. Orange textures and red marks on white paper fail; covered tags lose
/// only the covered element.
bool HasRing(const cv::Mat& bgr, const RedBlob& blob);

/// Same from a mask (tests).
std::vector<RedBlob> FindRedBlobs(const cv::Mat& mask, const BlobLimits& limits);

/// Whether an sRGB colour (codes 0 … 255) passes HasRing's test: LabApprox's a* < 10 and
/// L* < 85, decided by one table lookup that agrees with IsRingColourByLabApprox on every colour
/// (tested).
bool IsRingColour(int r, int g, int b);
/// The same rule evaluated through LabApprox: what the table is built from and tested against.
bool IsRingColourByLabApprox(int r, int g, int b);

}  // namespace pintag::stage
