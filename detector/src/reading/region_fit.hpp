#pragma once
// The free model: every one of the 50 regions its own colour, by least squares (ridge towards the
// mean). Its residual is what a blur is judged by, and its per-channel noise the unit of every
// margin the readers state.

#include <array>

#include "reading/region_system.hpp"

namespace pintag::reading {

template <int kChannels>
struct FreeFit {
  bool ok = false;
  std::array<std::array<double, kModelRegions>, kChannels> colour{};
  std::array<double, kChannels> residual{};     ///< sum of squares per channel
  std::array<double, kModelRegions> support{};  ///< AᵀA's diagonal: how much each region is seen
};

/// Least-squares region colours for `system` (ridge of 1 % of AᵀA's mean diagonal).
template <int kChannels>
FreeFit<kChannels> SolveFree(const RegionSystem<kChannels>& system);

extern template FreeFit<1> SolveFree<1>(const RegionSystem<1>&);
extern template FreeFit<2> SolveFree<2>(const RegionSystem<2>&);

}  // namespace pintag::reading
