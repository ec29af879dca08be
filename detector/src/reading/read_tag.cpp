#include "reading/read_tag.hpp"

#include <algorithm>
#include <chrono>
#include <string>
#include <utility>

#include "elapsed_ms.hpp"
#include "homography.hpp"
#include "reading/decision.hpp"
#include "reading/mosaic_reread.hpp"
#include "reading/rereading.hpp"
#include "reading/sampling.hpp"

namespace pintag::stage {
namespace {

using Clock = std::chrono::steady_clock;

// The model's codeword as an oriented reading, for the codec and the detection's cells.
OrientationResult AsOrientation(const reading::CodewordDecision& d) {
  OrientationResult o;
  o.ok = true;
  o.quarter_turns = d.quarter_turns;
  const TagCells cells = EncodeCells(*d.winner);
  for (int e = 0; e < kElements; ++e) {
    for (int g = 0; g < kGreenSectors; ++g) {
      o.reading.green[e][g] = cells.green[e][g] ? Bit::kOne : Bit::kZero;
      o.margins.green[e][g] = cells.green[e][g] ? 1 : -1;
    }
    for (int q = 0; q < kRedQuadrants; ++q) {
      o.reading.red[e][q] = cells.red[e][q] ? Bit::kOne : Bit::kZero;
      o.margins.red[e][q] = cells.red[e][q] ? 1 : -1;
    }
  }
  o.min_known_margin = 1;
  return o;
}

/// What a winner's re-reads found: a narrow square's (reading/rereading.hpp) or through a mosaic
/// (reading/mosaic_reread.hpp).
enum class RereadVerdict : std::uint8_t { kChosenAgain, kOtherWinner, kBudgetSpent };

/// Two more model reads, from `fitted` moved both ways, each taken from the budget first; their
/// times go to `times`.
RereadVerdict Reread(const cv::Mat& bgr, ChromaUpsampling upsampling,
                     const reading::Corners& fitted, TagKey winner, ModelBudget* budget,
                     ReadingTimes* times) {
  for (const double sign : {1.0, -1.0}) {
    if (budget != nullptr && !budget->take()) return RereadVerdict::kBudgetSpent;
    ++times->model_rereads;
    const reading::Reread again =
        reading::ReadAgain(bgr, upsampling, reading::MovedCorners(fitted, sign), winner);
    times->model_fit_ms += again.fit_ms;
    times->codeword_ms += again.codeword_ms;
    if (!again.same_winner) return RereadVerdict::kOtherWinner;
  }
  return RereadVerdict::kChosenAgain;
}

/// Reads of the winner through a mosaic of our own, one Bayer layout after another, until one
/// accepts it again (reading/mosaic_reread.hpp); each taken from the budget first, their times
/// going to `times`.
RereadVerdict RereadThroughMosaics(const cv::Mat& bgr, ChromaUpsampling upsampling,
                                   const reading::Corners& fitted, TagKey winner,
                                   ModelBudget* budget, ReadingTimes* times) {
  const reading::SquareCrop crop = reading::CropAroundCorners(bgr, fitted);
  if (crop.bgr.empty()) return RereadVerdict::kOtherWinner;
  for (int phase = 0; phase < reading::kMosaicPhases; ++phase) {
    if (budget != nullptr && !budget->take()) return RereadVerdict::kBudgetSpent;
    ++times->mosaic_rereads;
    const reading::MosaicReread again = reading::ReadThroughMosaic(crop, upsampling, winner, phase);
    times->model_fit_ms += again.fit_ms;
    times->codeword_ms += again.codeword_ms;
    if (again.accepted_again) return RereadVerdict::kChosenAgain;
  }
  return RereadVerdict::kOtherWinner;
}

/// Unless `verdict` is kChosenAgain, refuses the candidate's key, saying which re-reads were not
/// had (`unpaid`) or did not choose the winner (`not_chosen`); true when it refused.
bool RefusedByRereads(RereadVerdict verdict, const char* unpaid, const char* not_chosen,
                      CandidateReading* c) {
  if (verdict == RereadVerdict::kChosenAgain) return false;
  c->reading.payload.key.reset();
  c->times.model_skipped = verdict == RereadVerdict::kBudgetSpent;
  c->reading.payload.error =
      verdict == RereadVerdict::kBudgetSpent
          ? std::string("model: this frame's model reads are spent before ") + unpaid +
                " (max_model_reads)"
          : std::string("model: ") + not_chosen;
  return true;
}

}  // namespace

bool NeededRecovery(const PayloadResult& payload) {
  return payload.bit_from_parity || payload.bits_from_second_copy > 0;
}

int ElementsWithUnknownCells(const OrientationResult& orientation) {
  const CellReading& cells = orientation.reading;
  int elements = 0;
  for (int e = 0; e < kElements; ++e) {
    const auto unknown = [](Bit b) { return b == Bit::kUnknown; };
    if (std::any_of(cells.green[e].begin(), cells.green[e].end(), unknown) ||
        std::any_of(cells.red[e].begin(), cells.red[e].end(), unknown)) {
      ++elements;
    }
  }
  return elements;
}

PayloadResult DecodeReading(const OrientationResult& orientation) {
  // A 24 px tag read with 9 unknown bits, 4 from one copy, 1 from parity and a weakest bit at
  // 0.31 decoded to another key in the benchmark.
  PayloadResult payload = DecodePayload(orientation.reading);
  if (payload.key && NeededRecovery(payload) &&
      orientation.min_known_margin < kRecoveredReadingMinMargin) {
    payload.key.reset();
    payload.error = "bits recovered, but another bit is read too weakly to trust the rest";
  }
  return payload;
}

CandidateReading ReadCandidate(const cv::Mat& bgr, ChromaUpsampling upsampling, const Quad& quad,
                               const BitThresholds& thresholds,
                               const std::function<bool(const Quad&)>& accept_fitted,
                               ModelBudget* budget) {
  CandidateReading c;
  c.quad = quad;
  TagReading& r = c.reading;
  const auto t0 = Clock::now();
  r.orientation = ReadOrientation(SampleCells(bgr, HomographyFromQuad(quad)), thresholds);
  if (r.orientation.ok) r.payload = DecodeReading(r.orientation);
  const auto t1 = Clock::now();
  c.times.sample_ms = ElapsedMs(t0, t1);
  const double side = MeanSidePx(HomographyFromQuad(quad));
  const bool guessed = NeededRecovery(r.payload) && ElementsWithUnknownCells(r.orientation) > 1;
  if (r.payload.key && (!guessed || side > reading::kModelMaxSidePx)) {
    r.reader = Reader::kDirect;
    return c;
  }
  // The code's redundancy is laid out for one lost element (a covered one). A reading recovered
  // from unknown cells in several elements was read poorly throughout, and recovery spent the
  // redundancy that would have shown a misread bit, so the model decides it
  // (docs/DETECTOR-RESEARCH.md, "Recovered direct readings"). Small or blurred cells mix: the model
  // reads what direct samples could not.
  r.payload.key.reset();  // every path below gives the model's key or says why there is none
  if (side > reading::kModelMaxSidePx) return c;
  // Each side changes by at most twice a corner's shift: a square that cannot reach the least side
  // the codeword is read at would be refused after the fit (RefuseCodeword).
  if (side + 2 * reading::MaxCornerShiftPx(side) < reading::kMinSidePx) {
    r.payload.error = "model: square too small to read its codeword";
    return c;
  }
  if (budget != nullptr && !budget->take()) {
    c.times.model_skipped = true;
    r.payload.error = "model: this frame's model reads are spent (max_model_reads)";
    return c;
  }
  c.times.model_read = true;
  const reading::FittedModel model =
      reading::FitModel(bgr, upsampling, {quad[0], quad[1], quad[2], quad[3]}, &r.model.error);
  r.model.fit = model.fit;
  const auto t2 = Clock::now();
  c.times.model_fit_ms = ElapsedMs(t1, t2);
  // A fitted square under the least side is refused whatever its codeword (RefuseCodeword), so
  // its codeword is not searched for (a few milliseconds on 14-18 px squares).
  const reading::Corners& fitted = r.model.fit.corners;
  if (model.fit.ok && !reading::TooSmallToRead(fitted)) {
    r.model.decision = reading::DecideCodeword(model);
  }
  c.times.codeword_ms = ElapsedMs(t2, Clock::now());
  const std::string refused = reading::RefuseCodeword(r.model);
  if (!refused.empty()) {
    r.payload.key.reset();
    r.payload.error = "model: " + refused;
    return c;
  }
  const Quad moved{fitted[0], fitted[1], fitted[2], fitted[3]};
  if (accept_fitted && !accept_fitted(moved)) {
    r.payload.error = "model: the fitted square does not hold the candidate's elements";
    return c;
  }
  r.orientation = AsOrientation(r.model.decision);
  r.payload = DecodeReading(r.orientation);
  if (!r.payload.key || *r.payload.key != *r.model.decision.winner) {
    r.payload.key.reset();
    r.payload.error = "model: the codec refuses the codeword";
    return c;
  }
  // Then the dearest checks: on a narrow square the winner must be chosen again by two more reads
  // from moved corners (reading/rereading.hpp) ...
  if (reading::NeedsRereading(fitted) &&
      RefusedByRereads(Reread(bgr, upsampling, fitted, *r.model.decision.winner, budget, &c.times),
                       "the narrow square's winner was read again",
                       "a narrow square's winner not chosen again from moved corners", &c)) {
    return c;
  }
  // ... and a winner whose lead a demosaic's error could have made must be accepted again through
  // a mosaic of our own (reading/mosaic_reread.hpp).
  if (reading::NeedsMosaicCheck(r.model) &&
      RefusedByRereads(
          RereadThroughMosaics(bgr, upsampling, fitted, *r.model.decision.winner, budget, &c.times),
          "the winner was read again through a mosaic",
          "the winner is not accepted again through any Bayer mosaic", &c)) {
    return c;
  }
  r.reader = Reader::kModel;
  c.quad = moved;
  c.corners_fitted = true;
  return c;
}

}  // namespace pintag::stage
