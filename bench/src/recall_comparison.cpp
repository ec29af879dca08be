#include "recall_comparison.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace pintag::bench {
namespace {

// The binomial distribution's probabilities of 0 … n successes, by logarithms so that large n
// and rates near 0 or 1 neither overflow nor underflow into nonsense.
std::vector<double> BinomialPmf(int n, double p) {
  std::vector<double> pmf(static_cast<std::size_t>(n) + 1, 0.0);
  if (p <= 0) {
    pmf.front() = 1;
    return pmf;
  }
  if (p >= 1) {
    pmf.back() = 1;
    return pmf;
  }
  for (int k = 0; k <= n; ++k) {
    const double log_choose =
        std::lgamma(n + 1.0) - std::lgamma(k + 1.0) - std::lgamma(n - k + 1.0);
    pmf[static_cast<std::size_t>(k)] =
        std::exp(log_choose + k * std::log(p) + (n - k) * std::log1p(-p));
  }
  return pmf;
}

}  // namespace

double BinsBehindByChance::atMost(std::size_t k) const {
  double sum = 0;
  for (std::size_t i = 0; i <= k && i < probability.size(); ++i) sum += probability[i];
  return std::min(sum, 1.0);
}

BinsBehindByChance ChanceOfBinsBehind(std::span<const BinTally> reference_bins, BinRate rate) {
  BinsBehindByChance chance;
  chance.probability = {1.0};
  for (const BinTally& bin : reference_bins) {
    // Two independent counts of the same distribution: a tie or not, and by symmetry the rest
    // splits evenly between "fewer" and "more".
    double behind = 0;
    if (bin.tags > 0) {
      double tie = 0;
      const double p = rate == BinRate::kObserved ? static_cast<double>(bin.found) / bin.tags
                                                  : (bin.found + 0.5) / (bin.tags + 1.0);
      for (const double f : BinomialPmf(bin.tags, p)) {
        tie += f * f;
      }
      behind = std::max(0.0, (1 - tie) / 2);
    }
    chance.expected += behind;
    // The count of bins behind, one bin more: a sum of independent yes / no outcomes.
    std::vector<double> next(chance.probability.size() + 1, 0.0);
    for (std::size_t k = 0; k < chance.probability.size(); ++k) {
      next[k] += chance.probability[k] * (1 - behind);
      next[k + 1] += chance.probability[k] * behind;
    }
    chance.probability = std::move(next);
  }
  return chance;
}

RecallDifference CompareRecall(const PairedOutcomes& outcomes) {
  constexpr double kZ95 = 1.959964;  // the standard normal's 97.5th percentile
  RecallDifference difference;
  const int poses = outcomes.poses();
  if (poses <= 0) return difference;
  const double only_first = outcomes.only_first, only_second = outcomes.only_second;
  const double net = only_first - only_second;
  difference.points = 100 * net / poses;
  // Each pose adds +1, −1 or 0 to the net count: its variance over the poses, divided by n².
  const double variance = std::max(0.0, (only_first + only_second) - net * net / poses) /
                          (static_cast<double>(poses) * poses);
  const double half_width = 100 * kZ95 * std::sqrt(variance);
  difference.low = difference.points - half_width;
  difference.high = difference.points + half_width;
  const int discordant = outcomes.only_first + outcomes.only_second;
  if (discordant > 0) {
    const std::vector<double> pmf = BinomialPmf(discordant, 0.5);
    double tail = 0;
    for (int k = 0; k <= std::min(outcomes.only_first, outcomes.only_second); ++k) {
      tail += pmf[static_cast<std::size_t>(k)];
    }
    difference.p_value = std::min(1.0, 2 * tail);
  }
  return difference;
}

}  // namespace pintag::bench
