#pragma once
// Stage 4, homography: the quad's corners refined to sub-pixel by fitting a straight line to each
// edge of the black square (edge points found where the profile across the edge crosses halfway
// between the dark square and the white quiet zone), then the homography from tag units.

#include <array>
#include <opencv2/core.hpp>

#include "candidates/quads.hpp"

namespace pintag::stage {

/// Refines `quad` in place on `dark` (MinChannel of a region at `origin`). Returns false, leaving
/// the quad unchanged, when an edge has too few clean edge points.
bool RefineCorners(const cv::Mat& dark, cv::Point origin, Quad* quad);

/// Homography taking tag units (square corners (0,0) (1,0) (1,1) (0,1)) to the quad's corners,
/// with quad[i] the image of corner i.
cv::Matx33d HomographyFromQuad(const Quad& quad);

/// `quad` relabelled so that the old corner `first` becomes corner 0 (order kept).
Quad RotateQuad(const Quad& quad, int first);

cv::Point2d Apply(const cv::Matx33d& h, double u, double v);

/// The mean side (px) of the square that `tag_to_image` maps the unit square to.
double MeanSidePx(const cv::Matx33d& tag_to_image);

/// The square's extent (px) across its most foreshortened direction at its centre: the smaller
/// singular value of the map's derivative there. A frontal square of side s gives s; tilted by θ,
/// s cos θ whatever the direction of the tilt (exactly when its centre lies on the optical axis,
/// closely elsewhere).
double ShortExtentPx(const cv::Matx33d& tag_to_image);

}  // namespace pintag::stage
