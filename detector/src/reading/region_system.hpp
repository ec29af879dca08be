#pragma once
// The least-squares problem "which colour has each region": every sample is the blurred coverage
// of the regions times their colours. Its normal equations are summed once per blur; every model
// (free colours, the six-colour palette, each codeword) is then solved from them alone.

#include <array>
#include <vector>

#include "reading/region_coverage.hpp"
#include "reading/tag_samples.hpp"

namespace pintag::reading {

/// AᵀA, Aᵀy per channel, yᵀy per channel and the sample count of one system over the 50 regions.
template <int kChannels>
struct RegionSystem {
  std::array<double, std::size_t{kModelRegions} * kModelRegions> ata{};
  std::array<std::array<double, kModelRegions>, kChannels> aty{};
  std::array<double, kChannels> yty{};
  std::size_t samples = 0;
  double at(int j, int k) const {
    return ata[static_cast<std::size_t>(j) * kModelRegions + static_cast<std::size_t>(k)];
  }
};
using LumaSystem = RegionSystem<1>;    ///< luminance
using ChromaSystem = RegionSystem<2>;  ///< Cb, Cr: one blur, one AᵀA

/// The box a coverage must span for samples inside `bounds` under any kernel.
cv::Rect CoverageBox(const cv::Rect& bounds);

/// The luma system over every `stride`-th sample (with `by_position`: the samples whose position
/// hashes to a multiple of `stride`, the same pixels whatever homography made the coverage).
LumaSystem AccumulateLuma(const RegionCoverage& coverage, const std::vector<LumaSample>& samples,
                          const Kernel& kernel, std::size_t stride = 1, bool by_position = false);
ChromaSystem AccumulateChroma(const RegionCoverage& coverage,
                              const std::vector<ChromaSample>& samples, const Kernel& kernel,
                              std::size_t stride = 1);

/// The model's brightness at each sample for region colours `colours`.
std::vector<double> PredictLuma(const RegionCoverage& coverage,
                                const std::vector<LumaSample>& samples, const Kernel& kernel,
                                const std::array<double, kModelRegions>& colours);

}  // namespace pintag::reading
