#pragma once
// The last check a model winner meets (stage 5c): read again through a colour filter array of our
// own, it must still be accepted. A phone's demosaic and its JPEG leave an error in the pixels that
// is not noise; where blur has thinned the evidence between codewords, that error can decide the
// winner and still lead by more than the decision's thresholds ask. A winner that rests on the
// tag's evidence survives a little more error of that kind; one that rests on the error usually
// does not (docs/DETECTOR-RESEARCH.md, "A winner read again through a mosaic of our own"). It only
// refuses: RefuseCodeword's rules still decide everything else.

#include <opencv2/core.hpp>

#include "pintag/codec/tag_key.hpp"
#include "pintag/detector/chroma_upsampling.hpp"
#include "reading/model_reader.hpp"

namespace pintag::reading {

/// Winners that lead by at least this many independent samples (CountedLead over the chroma
/// residuals' variance inflation) are not checked: a round number well past the largest wrong lead
/// the tuning world has made with an edge-directed demosaic (56.8, seed 25 frame 2137), so that
/// the check's time goes to the readings whose lead such an error could have made.
inline constexpr double kMosaicCheckMaxIndependentLead = 100;

/// Pixels kept around the corners' bounding box in the re-mosaiced crop: more than the corner
/// refinement may move (MaxCornerShiftPx: at most 3 px) plus the blur search's reach.
inline constexpr int kMosaicCropMarginPx = 32;

/// The Bayer layouts tried, one after the other, until one re-read accepts the winner.
inline constexpr int kMosaicPhases = 4;

/// Whether this accepted model reading is checked: its independent lead is under
/// kMosaicCheckMaxIndependentLead.
bool NeedsMosaicCheck(const ModelReading& reading);

/// The part of a frame around a square: its corners' box plus kMosaicCropMarginPx, clipped to the
/// frame, with its origin at even coordinates so that a JPEG's 2 × 2 chroma blocks keep their
/// place. `corners` are the square's, in the crop's coordinates. Empty when a corner is not finite
/// or the box lies outside the frame.
struct SquareCrop {
  cv::Mat bgr;
  Corners corners{};
};
SquareCrop CropAroundCorners(const cv::Mat& bgr, const Corners& corners);

/// `bgr` (8-bit BGR) as a sensor with a Bayer colour filter array would give it after a bilinear
/// demosaic: each pixel keeps one colour, in `phase`'s layout (0 RGGB, 1 GRBG, 2 GBRG, 3 BGGR:
/// where red sits in each 2 × 2 cell), and the other two are interpolated from its neighbours.
cv::Mat Remosaic(const cv::Mat& bgr, int phase);

/// One re-read through the mosaic of `phase`: the model fitted on the re-mosaiced crop from the
/// crop's corners (the winner's fitted ones), then the decision's rules.
struct MosaicReread {
  bool accepted_again = false;  ///< a model fitted, and RefuseCodeword accepts the same winner
  double fit_ms = 0;
  double codeword_ms = 0;
};
MosaicReread ReadThroughMosaic(const SquareCrop& crop, ChromaUpsampling upsampling, TagKey winner,
                               int phase);

}  // namespace pintag::reading
