#pragma once
// Stage 5b, reading cells through a blur model. On a small or blurred tag each pixel mixes several
// cells (a green sector of a 32 px tag is about 4 px across; motion blur smears 5), so sampling
// near a cell's centre reads its neighbours too. Here every cell's colour is estimated at once
// instead: each pixel near the tag is modelled, in linear light, as the camera's blur applied to
// the tag's 50 regions (48 cells, the black square, the quiet zone), and the region colours that
// explain the pixels best are found by least squares. The blur is a Gaussian, round or elongated
// (as motion makes it), chosen by a small search for the smallest residual.
//
// The estimates come back as cell samples for the same orientation and codec checks as direct
// samples: nothing here decides a bit, so a tag read this way meets the same bar.

#include <opencv2/core.hpp>

#include "sampling.hpp"

namespace pintag::stage {

struct BlurFit {
  bool ok = false;
  CellSamples cells;          ///< each cell's fitted colour, as a*, b*
  double sigma_major_px = 0;  ///< the chosen blur: standard deviation along its long axis, px
  double sigma_minor_px = 0;  ///< … and across it, px
  double angle_deg = 0;       ///< direction of the long axis (image x towards y)
  double rms = 0;             ///< residual per pixel and channel, linear light (0 … 1)
  int evaluations = 0;        ///< blur candidates tried
};

/// Largest square side (px) the fit is tried on: above it cells are several pixels wide, direct
/// samples read them, and the fit's cost grows with the area.
inline constexpr double kBlurFitMaxSidePx = 100;

/// Fits the cells of the tag whose unit square maps to the image by `tag_to_image`.
BlurFit FitCellsThroughBlur(const cv::Mat& bgr, const cv::Matx33d& tag_to_image);

}  // namespace pintag::stage
