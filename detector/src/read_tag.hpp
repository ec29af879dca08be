#pragma once
// Stages 5 and 6 for one candidate square: every reader the detector has, in order, on the tag
// that the homography places. Direct samples first, then the blur model's fitted colours, then
// its two-colours-per-class bits, then the nearest codeword; the first reading the codec accepts
// wins, subject to the rules below that each exist because a wrong key got through without them.

#include <functional>
#include <opencv2/core.hpp>

#include "blur_model.hpp"
#include "orientation.hpp"
#include "payload.hpp"
#include "quads.hpp"

namespace pintag::stage {

/// The codec's verdict on an oriented reading, with one rule of the detector's own: a reading that
/// needed recovery (a bit from the other payload copy, or one from the parity) is refused unless
/// every bit it did read has a margin of at least kRecoveredReadingMinMargin.
inline constexpr double kRecoveredReadingMinMargin = 0.5;
PayloadResult DecodeReading(const OrientationResult& orientation);

/// The lead (noise units) by which the nearest codeword must beat every other codeword for a
/// candidate read on its own corners. kNearestCodewordMinLead (25) was set from the first wrong
/// keys logged in the sweeps; read from the true corners of tags of 14–48 px (a scratch probe,
/// seeds 1–6, 16 frames per bin, the exact corners and three with 0.5 px of noise on each
/// coordinate), wrong codewords that passed every other rule led by up to 71, all on 24 px tags
/// under hard light. At 75 the seed 1–3 sweeps lost 3 of 1,440 target-bin tags. (The shifted
/// fits that confirm a codeword still need only kNearestCodewordMinLead.)
inline constexpr double kNearestCodewordAcceptLead = 75;

/// On corners fitted to the pixels (FitCornersThroughBlur) the nearest codeword needs this lead
/// (noise units), not kNearestCodewordAcceptLead: the corners had eight coordinates of freedom to
/// follow the model.
inline constexpr double kFittedCornersNearestCodewordMinLead = 100;

/// … and this lead when it is not also the codeword nearest on the candidate's own corners
/// (whatever its lead there). Reading every tag of 14–48 px at seeds 7 and 8 at its true corners,
/// exactly and with 0.5 px of noise (8,960 readings), one gave a wrong key this way: own corners
/// with noise, nearest codeword 7506 at a lead of 18; fitted corners, 16878 for 16894 (one key bit)
/// at a lead of 114. Of the 240 right readings made on fitted corners there, 11 led by less than
/// 150 with another codeword nearest on the own corners; in the seed 1–3 sweeps, 1 of 35.
inline constexpr double kFittedCornersNewCodewordMinLead = 150;

/// When the blur fit ends at its widest blur (BlurFit::atBlurLimit) the nearest codeword needs
/// this lead, wherever the corners came from: the model then misses part of the blur. In the
/// probe above such fits gave 11 of the 18 wrong keys (at leads of 49–173; all 4 of those read
/// on fitted corners, at 102–166) from a tenth of the right readings.
inline constexpr double kBlurLimitNearestCodewordMinLead = 200;

/// A square whose sides average less than this (px) gets no nearest codeword: its cells (0.1 of
/// the side) are near two pixels across, the colour resolution JPEG keeps (4:2:0), while the bits
/// are in the colour. The detector read an 18 px tag in moderate light (seed 7, 16 frames per
/// bin, frame 1505) as key 543 for 539, one key bit apart, on corners averaging 20.1 px; at its
/// exact corners the model's free labelling was that codeword too. 22 rather than 20 leaves room
/// for corners a pixel outside the square.
inline constexpr double kNearestCodewordMinSidePx = 22;

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
  /// The nearest codeword's decision (its winner and lead whether accepted or not), when the
  /// readers got that far.
  CodewordReading nearest;
  bool throughBlurModel() const { return reader != Reader::kNone && reader != Reader::kDirect; }
};

/// Reads the tag whose unit square maps to the image by `tag_to_image`. Through the blur model, a
/// key read from the fitted colours is refused when another codeword explains the pixels better,
/// and one read from the two-colours-per-class bits unless it is the codeword explaining them
/// best (at the true corners of a 32 px tag under hard light the bits reading, with two bits
/// recovered from the other copy, gave a valid key two bits from the truth; the right codeword
/// explained the pixels better by 286 noise units). The nearest codeword itself needs a lead of
/// `nearest_min_lead`, or kBlurLimitNearestCodewordMinLead when the blur fit ended at its limit.
TagReading ReadTag(const cv::Mat& bgr, const cv::Matx33d& tag_to_image,
                   const BitThresholds& thresholds,
                   double nearest_min_lead = kNearestCodewordAcceptLead);

/// A candidate square read as the detector reads it: ReadTag on its corners, a nearest-codeword
/// reading confirmed where the corners fit the model best (the same codeword must be nearest
/// there); when no reader decodes and the blur model was fitted, the corners fitted through the
/// model (FitCornersThroughBlur) and read again, with the nearest codeword held to
/// kFittedCornersNearestCodewordMinLead. `accept_fitted`, when given, may refuse the fitted
/// square (the red path checks that its blobs still sit on the elements).
struct CandidateReading {
  TagReading reading;
  Quad quad{};                  ///< the corners the reading was made on
  bool corners_fitted = false;  ///< they are the fitted ones
};
CandidateReading ReadCandidate(const cv::Mat& bgr, const Quad& quad,
                               const BitThresholds& thresholds,
                               const std::function<bool(const Quad&)>& accept_fitted = {});

}  // namespace pintag::stage
