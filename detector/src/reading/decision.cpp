#include "reading/decision.hpp"

#include <algorithm>
#include <vector>

#include "homography.hpp"

namespace pintag::reading {

namespace {

cv::Matx33d SquareHomography(const Corners& corners) {
  return stage::HomographyFromQuad({corners[0], corners[1], corners[2], corners[3]});
}

}  // namespace

bool TooSmallToRead(const Corners& corners) {
  return stage::MeanSidePx(SquareHomography(corners)) < kMinSidePx;
}

bool IsNarrow(const Corners& corners) {
  // Written so that a degenerate square (no finite extent) counts as narrow: the stricter rule.
  return !(stage::ShortExtentPx(SquareHomography(corners)) >= kNarrowExtentPx);
}

double CountedLead(const ModelReading& reading) {
  // A noise that is not a number makes the lead one too, which RefuseCodeword refuses.
  const double noise = reading.fit.luma_noise;
  const double scale =
      noise >= kLumaNoiseFloor ? 1.0 : (noise / kLumaNoiseFloor) * (noise / kLumaNoiseFloor);
  return reading.decision.lead * scale;
}

std::string RefuseCodeword(const ModelReading& reading) {
  const CodewordDecision& d = reading.decision;
  if (!reading.fit.ok) return reading.error.empty() ? "no model fitted" : reading.error;
  // Before the winner: ReadCandidate does not search a codeword for a square this small.
  if (TooSmallToRead(reading.fit.corners)) return "square too small to read its codeword";
  if (!d.winner) return "no codeword candidates";
  const double inflation = VarianceInflation(reading.fit.chroma_correlation);
  const bool fits = d.excess <= kMaxExcess;
  const bool narrow = IsNarrow(reading.fit.corners);
  const double least_independent_lead = !fits    ? kMinIndependentLead
                                        : narrow ? kMinIndependentLeadOfANarrowFit
                                                 : kMinIndependentLeadOfAFit;
  // Written so that a statistic that is not a number refuses (as IsNarrow does).
  const double lead = CountedLead(reading);
  if (!(lead >= kMinLead) || !(lead / inflation >= least_independent_lead)) {
    return "no codeword clearly nearest";
  }
  if ((!fits && !(d.excess / inflation <= kMaxIndependentExcess)) ||
      (narrow && !(d.excess <= kMaxNarrowExcess))) {
    return "codeword explains the pixels worse than its cells read freely";
  }
  if (!(d.chroma_deficit <= kMaxChromaDeficit)) return "colour prefers another codeword";
  // The colours must be a tag's: every cell level between the black and the quiet zone in
  // luminance, and red redder (higher Cr) than green by a clear step (the palette's reds sit at
  // Cr +0.34, its greens at −0.07 and −0.30; casts move all four together).
  const auto& c = d.colours;
  const std::uint64_t code = Codebook()[d.winner->value()];
  const std::uint64_t greens = code & 0xFFFFFFFFU;
  std::vector<int> levels = {kRed0, kRed1};
  if (greens != 0xFFFFFFFFU) levels.push_back(kGreen0);
  if (greens != 0) levels.push_back(kGreen1);
  const double least_red_cr = std::min(c[kRed0][2], c[kRed1][2]);
  double most_green_cr = -1;
  const double black = c[kBlackLevel][0];
  const double quiet = c[kQuietLevel][0];
  for (const int level : levels) {
    const double y = c[static_cast<std::size_t>(level)][0];
    if (!(y - black >= kMinLevelAboveBlack * (quiet - black) && y < quiet))
      return "codeword's colours are not a tag's";
    if (level == kGreen0 || level == kGreen1) {
      most_green_cr = std::max(most_green_cr, c[static_cast<std::size_t>(level)][2]);
    }
  }
  if (least_red_cr - most_green_cr < kMinRedOverGreenCr)
    return "codeword's colours are not a tag's";
  return {};
}

}  // namespace pintag::reading
