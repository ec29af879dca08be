#pragma once
// Stages 5 and 6 for one candidate square: every reader the detector has, in order, on the tag
// that the homography places. Direct samples first, then the blur model's fitted colours, then
// its two-colours-per-class bits, then the nearest codeword; the first reading the codec accepts
// wins, subject to the rules below that each exist because a wrong key got through without them.

#include <opencv2/core.hpp>

#include "blur_model.hpp"
#include "orientation.hpp"
#include "payload.hpp"

namespace pintag::stage {

/// The codec's verdict on an oriented reading, with one rule of the detector's own: a reading that
/// needed recovery (a bit from the other payload copy, or one from the parity) is refused unless
/// every bit it did read has a margin of at least kRecoveredReadingMinMargin.
inline constexpr double kRecoveredReadingMinMargin = 0.5;
PayloadResult DecodeReading(const OrientationResult& orientation);

/// On corners fitted to the pixels (FitCornersThroughBlur) the nearest codeword needs this lead
/// (noise units), not kNearestCodewordMinLead: the corners had eight coordinates of freedom to
/// follow the model.
inline constexpr double kFittedCornersNearestCodewordMinLead = 100;

/// Which reader decided.
enum class Reader : std::uint8_t {
  kNone,            ///< no reader decoded
  kDirect,          ///< samples near the cell centres
  kModelColours,    ///< the blur model's fitted cell colours, thresholded as direct samples
  kModelBits,       ///< the blur model's two-colours-per-class labelling
  kNearestCodeword  ///< the codeword explaining the pixels best, by a lead, confirmed
};

struct TagReading {
  OrientationResult orientation;
  PayloadResult payload;
  Reader reader = Reader::kNone;
  BlurFit fit;  ///< ok when the direct samples did not decode and the model was fitted
  bool throughBlurModel() const { return reader != Reader::kNone && reader != Reader::kDirect; }
};

/// Reads the tag whose unit square maps to the image by `tag_to_image`. A key read through the
/// blur model by its colours or its bits is refused when another codeword explains the pixels
/// better (at the true corners of a 32 px tag under hard light the bits reading, with two bits
/// recovered from the other copy, gave a valid key two bits from the truth; the right codeword
/// explained the pixels better by 286 noise units).
TagReading ReadTag(const cv::Mat& bgr, const cv::Matx33d& tag_to_image,
                   const BitThresholds& thresholds,
                   double nearest_min_lead = kNearestCodewordMinLead);

}  // namespace pintag::stage
