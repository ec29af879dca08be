#pragma once
// The least-squares problem "which colour has each region": every sample is the blurred coverage
// of the regions times their colours. Its normal equations are summed once per blur; every model
// (free colours, the six-colour palette, each codeword) is then solved from them alone.

#include <array>
#include <span>
#include <vector>

#include "reading/region_coverage.hpp"
#include "reading/tag_samples.hpp"

namespace pintag::reading {

/// Where AᵀA's entry (j, k) is kept.
inline std::size_t AtaIndex(int j, int k) {
  return (static_cast<std::size_t>(j) * kModelRegions) + static_cast<std::size_t>(k);
}

/// AᵀA, Aᵀy per channel, yᵀy per channel, the sample count and the samples' total weight of one
/// system over the 50 regions.
template <int kChannels>
struct RegionSystem {
  std::array<double, std::size_t{kModelRegions} * kModelRegions> ata{};
  std::array<std::array<double, kModelRegions>, kChannels> aty{};
  std::array<double, kChannels> yty{};
  std::size_t samples = 0;
  double weight = 0;  ///< the samples' total weight (their count when unweighted)
  double at(int j, int k) const { return ata[AtaIndex(j, k)]; }
};
using LumaSystem = RegionSystem<1>;    ///< luminance
using ChromaSystem = RegionSystem<2>;  ///< Cb, Cr: one blur, one AᵀA

/// The box a coverage must span for samples inside `bounds` under any kernel.
cv::Rect CoverageBox(const cv::Rect& bounds);

/// The luma system over every `stride`-th sample (with `by_position`: the samples whose position
/// hashes to a multiple of `stride`, the same pixels whatever homography made the coverage).
LumaSystem AccumulateLuma(const RegionCoverage& coverage, const std::vector<LumaSample>& samples,
                          const Kernel& kernel, std::size_t stride = 1, bool by_position = false);

/// Luma samples' rows of the system (each sample's value and blurred coverage by the regions it
/// touches), kept so that the system can be summed again under other sample weights without
/// blurring the coverage again.
class LumaRows {
 public:
  struct Term {
    int region = 0;
    double weight = 0;
  };
  std::size_t size() const { return values_.size(); }
  double value(std::size_t i) const { return values_[i]; }
  std::span<const Term> terms(std::size_t i) const {
    return {terms_.data() + first_[i], first_[i + 1] - first_[i]};
  }
  void add(double value, const SampleWeights& weights);
  void reserve(std::size_t samples) {
    values_.reserve(samples);
    first_.reserve(samples + 1);
    terms_.reserve(samples * 4);
  }

 private:
  std::vector<double> values_;
  std::vector<std::size_t> first_{0};
  std::vector<Term> terms_;
};

/// The rows of every `stride`-th sample.
LumaRows GatherLumaRows(const RegionCoverage& coverage, const std::vector<LumaSample>& samples,
                        const Kernel& kernel, std::size_t stride = 1);

/// The luma system of `rows`, row i weighted by `weights[i]` (every row by 1 when empty;
/// otherwise one non-negative weight per row).
LumaSystem AccumulateLuma(const LumaRows& rows, std::span<const double> weights = {});

ChromaSystem AccumulateChroma(const RegionCoverage& coverage,
                              const std::vector<ChromaSample>& samples, const Kernel& kernel,
                              std::size_t stride = 1);

/// The model's brightness at each sample for region colours `colours`.
std::vector<double> PredictLuma(const RegionCoverage& coverage,
                                const std::vector<LumaSample>& samples, const Kernel& kernel,
                                const std::array<double, kModelRegions>& colours);

}  // namespace pintag::reading
