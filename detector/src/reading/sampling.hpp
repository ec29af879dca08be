#pragma once
// Stage 5, sampling: each red quadrant and green sector is sampled at a few points near its centre
// through the homography; each point's colour is bilinearly interpolated and converted with the
// integer LabApprox. A cell's value is the median over its points.

#include <opencv2/core.hpp>

#include "pintag/codec/cells.hpp"

namespace pintag::stage {

struct CellSample {
  double a = 0;         ///< median a*
  double b = 0;         ///< median b*
  double b_spread = 0;  ///< max − min b* over the cell's points
  bool valid = false;   ///< all points were inside the image
};

/// Cells in the frame of `tag_to_image` (element e is the one nearest tag corner e).
using CellSamples = BasicCells<CellSample>;

CellSamples SampleCells(const cv::Mat& bgr, const cv::Matx33d& tag_to_image);

}  // namespace pintag::stage
