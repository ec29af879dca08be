#include "read_tag.hpp"

#include <algorithm>
#include <array>
#include <optional>
#include <utility>

#include "corner_fit.hpp"
#include "homography.hpp"
#include "sampling.hpp"

namespace pintag::stage {
namespace {

// A codeword chosen through the blur model must not hang on the exact corners. The fit is
// repeated with the tag shifted by half a pixel each way and scaled by ±2 % (corner refinement is
// good to a few tenths of a pixel); at least two of those fits must choose the same codeword and
// none another. Measured on the benchmark: a 80 px tag at 78°, hard light, chose a codeword one
// key bit from the truth with a lead of 334 noise units, but only 1 of the 6 shifted fits agreed
// (5 chose none). Logged over seeds 1 to 6 (4,704 tagged frames), 203 nearest-codeword readings
// passed the lead and excess rules, all of them the right key: 41 were confirmed by exactly 2
// shifted fits, 18 by 1, 3 by none, and 1 met a fit choosing another key. Requiring 2 rather
// than 3 found 40 more tags in those sweeps, and their 12 runs (with and without the colour
// cast) read no wrong key.
constexpr int kJitteredFits = 6;
constexpr int kJitteredFitsToAgree = 2;

bool NearestCodewordIsStable(const cv::Mat& bgr, const cv::Matx33d& h, TagKey key) {
  constexpr std::array<std::array<double, 3>, kJitteredFits> kJitters{
      {{0.5, 0, 1}, {-0.5, 0, 1}, {0, 0.5, 1}, {0, -0.5, 1}, {0, 0, 1.02}, {0, 0, 0.98}}};
  const cv::Point2d centre = Apply(h, 0.5, 0.5);
  int agree = 0;
  for (const auto& [dx, dy, scale] : kJitters) {
    const cv::Matx33d moved(scale, 0, (1 - scale) * centre.x + dx,  //
                            0, scale, (1 - scale) * centre.y + dy,  //
                            0, 0, 1);
    const BlurFit fit = FitCellsThroughBlur(bgr, moved * h);
    if (!fit.ok) continue;
    // Confirmation must be clean: a shifted fit agrees only if its winner explains the pixels at
    // least as well as its free reading (no excused excess). With the excuse, a frame once misread
    // (bench/misread_regressions_test.cpp) found 4 of 6 shifted fits "agreeing" on the wrong key.
    const CodewordReading again = NearestCodewordThroughBlur(
        fit, SettleOrientations(fit), kNearestCodewordMinLead, /*excuse_small_excess=*/false);
    if (!again.key) continue;
    if (*again.key != key) return false;
    ++agree;
  }
  return agree >= kJitteredFitsToAgree;
}

// A codeword chosen on a candidate's own corners must stay the nearest where the corners fit the
// pixels best. Read at the true corners with 0.5 px of noise on each coordinate (a scratch probe
// over seeds 1–6, tags of 14–48 px), some nearest-codeword readings that passed every other rule
// were the wrong key, at leads of 35–173 noise units, beside about 4,000 right ones: the corners
// put the grid where another codeword fitted. Moved to where the free model fits best
// (FitCornersThroughBlur), the codeword chosen there was another key, or none, on most of the
// wrong ones, and the same on about 90 % of the right ones. In the seed 1–3 sweeps the rule cost
// 3 tags of 1,440 in the target bins. Squares the corner fit leaves alone (over 64 px, where
// cells are 6 px and more) are not asked.
bool NearestCodewordSurvivesCornerFit(const cv::Mat& bgr, const Quad& quad,
                                      const TagReading& reading) {
  const CornerFit fitted = FitCornersThroughBlur(bgr, quad, reading.fit);
  if (!fitted.moved) return true;  // the corners are where the model puts them (or too large)
  const BlurFit fit = FitCellsThroughBlur(bgr, HomographyFromQuad(fitted.quad));
  if (!fit.ok) return false;
  const CodewordReading there =
      NearestCodewordThroughBlur(fit, SettleOrientations(fit), /*min_margin=*/0);
  return there.key && reading.payload.key && *there.key == *reading.payload.key;
}

OrientationResult AsOrientation(const ModelReading& bits) {
  OrientationResult o;
  o.ok = true;
  o.quarter_turns = bits.quarter_turns;
  o.reading = bits.reading;
  o.margins = bits.margins;
  o.unknown = bits.unknown;
  o.min_known_margin = bits.min_known_margin;
  return o;
}

OrientationResult AsOrientation(const CodewordReading& nearest) {
  OrientationResult o;
  o.ok = true;
  o.quarter_turns = nearest.quarter_turns;
  o.reading = nearest.reading;
  o.min_known_margin = 1;
  return o;
}

}  // namespace

PayloadResult DecodeReading(const OrientationResult& orientation) {
  // A 24 px tag read with 9 unknown bits, 4 from one copy, 1 from parity and a weakest bit at
  // 0.31 decoded to another key in the benchmark.
  PayloadResult payload = DecodePayload(orientation.reading);
  const bool recovered = payload.bit_from_parity || payload.bits_from_second_copy > 0;
  if (payload.key && recovered && orientation.min_known_margin < kRecoveredReadingMinMargin) {
    payload.key.reset();
    payload.error = "bits recovered, but another bit is read too weakly to trust the rest";
  }
  return payload;
}

TagReading ReadTag(const cv::Mat& bgr, const cv::Matx33d& tag_to_image,
                   const BitThresholds& thresholds, double nearest_min_lead) {
  TagReading r;
  r.orientation = ReadOrientation(SampleCells(bgr, tag_to_image), thresholds);
  if (r.orientation.ok) r.payload = DecodeReading(r.orientation);
  if (r.payload.key) {
    r.reader = Reader::kDirect;
    return r;
  }
  // Small or blurred cells mix: read them through a blur model.
  r.fit = FitCellsThroughBlur(bgr, tag_to_image);
  const BlurFit& fit = r.fit;
  if (!fit.ok) return r;
  const auto accept = [&](OrientationResult orientation, PayloadResult payload, Reader reader) {
    r.orientation = std::move(orientation);
    r.payload = std::move(payload);
    r.reader = reader;
    return std::move(r);
  };

  // The codeword explaining the pixels best, found once: the fitted colours' reading must not
  // contradict it, the two-colours-per-class reading must be it, and it is the last reader
  // itself. (Over the probe's seeds 1–6, 4,829 right readings of the bits model all were the
  // nearest codeword, and its 3 wrong ones were not: twice another codeword was nearer, once the
  // nearest was refused for explaining the pixels worse than the free reading. The fitted
  // colours read 2,146 right keys and no wrong one; on 13 the nearest codeword was refused.)
  std::optional<SettledOrientations> settled;
  std::optional<CodewordReading> nearest;
  const auto nearest_codeword = [&]() -> const CodewordReading& {
    if (!settled) settled = SettleOrientations(fit);
    if (!nearest) nearest = NearestCodewordThroughBlur(fit, *settled, /*min_margin=*/0);
    return *nearest;
  };
  const auto uncontradicted = [&](TagKey key) {
    const CodewordReading& best = nearest_codeword();
    return !best.key || *best.key == key;
  };
  const auto is_nearest = [&](TagKey key) {
    const CodewordReading& best = nearest_codeword();
    return best.key && *best.key == key;
  };

  OrientationResult modelled = ReadOrientation(fit.cells, thresholds);
  if (modelled.ok) {
    PayloadResult payload = DecodeReading(modelled);
    if (payload.key && uncontradicted(*payload.key)) {
      return accept(std::move(modelled), std::move(payload), Reader::kModelColours);
    }
  }
  if (!settled) settled = SettleOrientations(fit);
  const ModelReading bits = ReadBitsThroughBlur(fit, *settled);
  if (bits.ok) {
    OrientationResult as_read = AsOrientation(bits);
    PayloadResult payload = DecodeReading(as_read);
    if (payload.key && is_nearest(*payload.key)) {
      return accept(std::move(as_read), std::move(payload), Reader::kModelBits);
    }
  }
  // Single bits do not decode: the codeword that explains the pixels clearly best, if one does.
  // (Its lead is measured whatever the bar; a reading refused at a lead of 0 is refused at any.)
  const CodewordReading& best = nearest_codeword();
  r.nearest = best;
  if (fit.atBlurLimit())
    nearest_min_lead = std::max(nearest_min_lead, kBlurLimitNearestCodewordMinLead);
  if (!best.key || best.lead < nearest_min_lead) return r;
  if (MeanSidePx(tag_to_image) < kNearestCodewordMinSidePx) return r;
  OrientationResult as_read = AsOrientation(best);
  PayloadResult payload = DecodeReading(as_read);
  if (payload.key && *payload.key == *best.key &&
      NearestCodewordIsStable(bgr, tag_to_image, *best.key)) {
    return accept(std::move(as_read), std::move(payload), Reader::kNearestCodeword);
  }
  return r;
}

CandidateReading ReadCandidate(const cv::Mat& bgr, const Quad& quad,
                               const BitThresholds& thresholds,
                               const std::function<bool(const Quad&)>& accept_fitted) {
  CandidateReading c;
  c.quad = quad;
  c.reading = ReadTag(bgr, HomographyFromQuad(quad), thresholds);
  if (c.reading.reader == Reader::kNearestCodeword &&
      !NearestCodewordSurvivesCornerFit(bgr, quad, c.reading)) {
    c.reading.payload.key.reset();
    c.reading.payload.error = "nearest codeword not confirmed where the corners fit best";
    c.reading.reader = Reader::kNone;
    return c;
  }
  if (c.reading.payload.key || !c.reading.fit.ok) return c;
  // No reader decoded it: the corners may be off by more than small cells allow.
  const CornerFit fitted = FitCornersThroughBlur(bgr, quad, c.reading.fit);
  if (!fitted.moved) return c;
  TagReading again = ReadTag(bgr, HomographyFromQuad(fitted.quad), thresholds,
                             kFittedCornersNearestCodewordMinLead);
  if (!again.payload.key || (accept_fitted && !accept_fitted(fitted.quad))) return c;
  // A codeword that only became the nearest once the corners moved needs a larger lead: the
  // corners may have followed the model towards it.
  if (again.reader == Reader::kNearestCodeword &&
      again.nearest.lead < kFittedCornersNewCodewordMinLead &&
      c.reading.nearest.winner != again.payload.key) {
    c.reading.payload.error = "nearest codeword on fitted corners is not the nearest on the own";
    return c;
  }
  c.reading = std::move(again);
  c.quad = fitted.quad;
  c.corners_fitted = true;
  return c;
}

}  // namespace pintag::stage
