#pragma once
// How often the model reader would accept a wrong codeword, for rates too small to count. The
// reader probe logs, for every reading, the winner's lead; the wrong winners that pass every
// check but the lead are the misreads a lead threshold stands between. Their leads fall off
// exponentially past a few units (docs/DETECTOR-RESEARCH.md, "The misread rate, measured by its
// tail"), so the share of readings whose wrong winner leads by more than T is estimated from the
// exceedances over a low threshold u: (count above u / readings) × exp(−(T − u) / scale), with
// scale the mean exceedance (the maximum-likelihood exponential fit).

#include <cstddef>
#include <span>

namespace pintag::bench {

struct LeadTail {
  std::size_t readings = 0;  ///< every reading of the probe, right, wrong or unread
  double from = 0;           ///< u: the fit uses wrong leads above this
  std::size_t above = 0;     ///< wrong leads above `from`
  double scale = 0;          ///< mean of (lead − from) over them: the tail's e-folding length
  /// Estimated share of readings with a wrong winner leading by more than `lead` (≥ from); 0 when
  /// nothing was above `from`.
  double rateAbove(double lead) const;
  /// The lead above which that share is `rate`: the inverse of rateAbove (`from` when nothing was
  /// above it).
  double leadFor(double rate) const;
};

/// The exponential tail of `wrong_leads` (one per wrong winner that passes every check but the
/// lead) above `from`, out of `readings` readings.
LeadTail FitLeadTail(std::span<const double> wrong_leads, std::size_t readings, double from);

}  // namespace pintag::bench
