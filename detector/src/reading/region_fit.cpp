#include "reading/region_fit.hpp"

#include <opencv2/core.hpp>

namespace pintag::reading {

template <int kChannels>
FreeFit<kChannels> SolveFree(const RegionSystem<kChannels>& system) {
  FreeFit<kChannels> fit;
  if (system.samples == 0 || !(system.weight > 0)) return fit;
  using Square = cv::Matx<double, kModelRegions, kModelRegions>;
  Square m;
  double trace = 0;
  for (int a = 0; a < kModelRegions; ++a) {
    for (int b = 0; b < kModelRegions; ++b) m(a, b) = system.at(a, b);
    trace += m(a, a);
    fit.support[static_cast<std::size_t>(a)] = m(a, a);
  }
  // A little ridge towards the mean keeps regions the samples barely see from swinging.
  const double ridge = 0.01 * trace / kModelRegions;
  Square ridged = m;
  for (int a = 0; a < kModelRegions; ++a) ridged(a, a) += ridge;
  // The samples' total weight: Σ Aᵀy over regions is Σ weight · y (coverage sums to one per
  // sample, kernels to one), so this gives the weighted mean whatever scale the weights have.
  const double n = system.weight;
  for (int ch = 0; ch < kChannels; ++ch) {
    cv::Matx<double, kModelRegions, 1> rhs, x;
    double mean = 0;
    for (int a = 0; a < kModelRegions; ++a) mean += system.aty[ch][static_cast<std::size_t>(a)];
    mean /= n;
    for (int a = 0; a < kModelRegions; ++a) {
      rhs(a) = system.aty[ch][static_cast<std::size_t>(a)] + ridge * mean;
    }
    if (!cv::solve(ridged, rhs, x, cv::DECOMP_CHOLESKY)) return fit;
    const cv::Matx<double, kModelRegions, 1> mx = m * x;
    double residual = system.yty[ch];
    for (int a = 0; a < kModelRegions; ++a) {
      residual += x(a) * (mx(a) - 2 * system.aty[ch][static_cast<std::size_t>(a)]);
      fit.colour[ch][static_cast<std::size_t>(a)] = x(a);
    }
    fit.residual[ch] = std::max(0.0, residual);
  }
  fit.ok = true;
  return fit;
}

template FreeFit<1> SolveFree<1>(const RegionSystem<1>&);
template FreeFit<2> SolveFree<2>(const RegionSystem<2>&);

}  // namespace pintag::reading
