#pragma once
// Stages 5 and 6 for one candidate square: the readers in order. Direct samples near the cell
// centres first (fast, and enough for any tag whose cells are a few pixels across); then, for a
// square of at most kModelMaxSidePx, the model of what the photo holds (reading/model_reader.hpp),
// which moves the corners to where the model fits and decides the codeword over the whole code.

#include <atomic>
#include <functional>
#include <opencv2/core.hpp>

#include "candidates/quads.hpp"
#include "pintag/detector/chroma_upsampling.hpp"
#include "reading/model_reader.hpp"
#include "reading/orientation.hpp"
#include "reading/payload.hpp"

namespace pintag::stage {

/// Whether the codec needed recovery for this key: a bit from the other payload copy, or one from
/// the parity. Such a key has no redundancy left to show a wrongly read bit.
bool NeededRecovery(const PayloadResult& payload);

/// How many of the four elements hold a cell read as unknown.
int ElementsWithUnknownCells(const OrientationResult& orientation);

/// The codec's verdict on an oriented reading, with one rule of the detector's own: a reading that
/// needed recovery is refused unless every bit it did read has a margin of at least
/// kRecoveredReadingMinMargin. (ReadCandidate asks more of it: when its unknown cells lie in more
/// than one element, the model reader decides the key instead, for squares up to kModelMaxSidePx.)
inline constexpr double kRecoveredReadingMinMargin = 0.5;
PayloadResult DecodeReading(const OrientationResult& orientation);

/// Which reader decided.
enum class Reader : std::uint8_t {
  kNone,    ///< no reader decoded
  kDirect,  ///< samples near the cell centres, thresholded
  kModel    ///< the codeword the model of the pixels chose, by a lead
};

struct TagReading {
  OrientationResult orientation;
  PayloadResult payload;
  Reader reader = Reader::kNone;
  reading::ModelReading model;  ///< when the model was tried (fit.ok)
  bool throughModel() const { return reader == Reader::kModel; }
};

/// The model reads one frame may still make (DetectorOptions::max_model_reads), shared by the
/// frame's worker threads.
class ModelBudget {
 public:
  explicit ModelBudget(int reads) : left_(reads) {}
  /// Takes one read; false when none is left.
  bool take() { return left_.fetch_sub(1) > 0; }

 private:
  std::atomic<int> left_;
};

/// What reading one candidate cost, by stage.
struct ReadingTimes {
  double sample_ms = 0;     ///< 5a + 6: direct samples, orientation, payload
  double model_fit_ms = 0;  ///< 5b
  double codeword_ms = 0;   ///< 5c + 6 for the model's codeword
  bool model_read = false;
  bool model_skipped = false;  ///< the budget was spent, before its read or one of its re-reads
  int model_rereads = 0;       ///< more reads of a narrow square's winner (their times included)
  int mosaic_rereads = 0;      ///< reads of the winner through a mosaic (their times included)
};

/// A candidate square read as the detector reads it, in `bgr` whose colour was decoded with
/// `upsampling`. When the model decides, the corners are the ones it refined; `accept_fitted`,
/// when given, may refuse them (the red path checks that its blobs still sit on the elements).
/// Without a budget the model may always read.
struct CandidateReading {
  TagReading reading;
  Quad quad{};                  ///< the corners the reading was made on
  bool corners_fitted = false;  ///< they are the model's
  ReadingTimes times;
};
CandidateReading ReadCandidate(const cv::Mat& bgr, ChromaUpsampling upsampling, const Quad& quad,
                               const BitThresholds& thresholds,
                               const std::function<bool(const Quad&)>& accept_fitted = {},
                               ModelBudget* budget = nullptr);

}  // namespace pintag::stage
