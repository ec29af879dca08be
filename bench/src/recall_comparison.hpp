#pragma once
// How far apart two detectors' recall on the same poses is, beyond what the sample's size alone
// would make of two equal detectors. The sweep renders every pose once per marker, so the
// comparison is paired: a pose counts only by what one detector found and the other did not.

#include <cstddef>
#include <span>
#include <vector>

namespace pintag::bench {

/// A bin of poses as the reference detector scored it (metrics.hpp's Tally, kept apart so that
/// these statistics need nothing of the sweep).
struct BinTally {
  int tags = 0;
  int found = 0;
};

/// The number of bins in which a detector finds fewer tags than the reference, when in every bin
/// both find each tag independently with the reference's own rate there (found / tags): what a
/// detector exactly as good as the reference would score, by chance alone, if its misses were
/// independent of the reference's. On the same poses they are not (a hard pose is hard for both),
/// which makes trailing rarer than this: it bounds what chance does, from above.
struct BinsBehindByChance {
  double expected = 0;
  std::vector<double> probability;  ///< [k]: the chance of being behind in exactly k bins
  /// The chance of being behind in at most k bins.
  double atMost(std::size_t k) const;
};
/// How a bin's rate is estimated from the reference's count in it.
enum class BinRate {
  kObserved,  ///< found / tags: a bin the reference found whole can never be trailed in
  kSmoothed,  ///< (found + ½) / (tags + 1): no bin's rate taken as certainly 0 or 1
};
BinsBehindByChance ChanceOfBinsBehind(std::span<const BinTally> reference_bins,
                                      BinRate rate = BinRate::kObserved);

/// What each of two detectors found on the same poses.
struct PairedOutcomes {
  int both = 0;
  int only_first = 0;
  int only_second = 0;
  int neither = 0;
  int poses() const { return both + only_first + only_second + neither; }
};

/// The first detector's recall minus the second's on paired poses, in points (percent), with its
/// normal 95 % interval, and McNemar's exact two-sided test of equal recall: the chance, if both
/// were equally good, of the discordant poses splitting at least this unevenly.
struct RecallDifference {
  double points = 0;
  double low = 0;
  double high = 0;
  double p_value = 1;
};
RecallDifference CompareRecall(const PairedOutcomes& outcomes);

}  // namespace pintag::bench
