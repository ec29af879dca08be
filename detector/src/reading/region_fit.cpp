#include "reading/region_fit.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace pintag::reading {
namespace {

constexpr int kN = kModelRegions;
using Square = std::array<double, std::size_t{kN} * kN>;

// Cholesky factorisation m = L Lᵀ in place (the lower triangle, each diagonal entry stored as its
// reciprocal), then L Lᵀ x = b for each of the kChannels right-hand sides b[·][ch], in place. The
// same operations in the same order as cv::solve(…, DECOMP_CHOLESKY), so the same bits, without
// its matrix copies and with one factorisation for both chroma channels. False, as there, when a
// pivot falls below machine epsilon.
template <int kChannels>
bool SolveCholesky(Square& m, std::array<std::array<double, kChannels>, kN>& b) {
  const auto at = [&](int i, int j) -> double& {
    return m[static_cast<std::size_t>(i) * kN + static_cast<std::size_t>(j)];
  };
  for (int i = 0; i < kN; ++i) {
    for (int j = 0; j < i; ++j) {
      double s = at(i, j);
      for (int k = 0; k < j; ++k) s -= at(i, k) * at(j, k);
      at(i, j) = s * at(j, j);
    }
    double s = at(i, i);
    for (int k = 0; k < i; ++k) s -= at(i, k) * at(i, k);
    if (s < std::numeric_limits<double>::epsilon()) return false;
    at(i, i) = 1. / std::sqrt(s);
  }
  for (int i = 0; i < kN; ++i) {  // L y = b
    for (int ch = 0; ch < kChannels; ++ch) {
      double s = b[static_cast<std::size_t>(i)][static_cast<std::size_t>(ch)];
      for (int k = 0; k < i; ++k) {
        s -= at(i, k) * b[static_cast<std::size_t>(k)][static_cast<std::size_t>(ch)];
      }
      b[static_cast<std::size_t>(i)][static_cast<std::size_t>(ch)] = s * at(i, i);
    }
  }
  for (int i = kN - 1; i >= 0; --i) {  // Lᵀ x = y
    for (int ch = 0; ch < kChannels; ++ch) {
      double s = b[static_cast<std::size_t>(i)][static_cast<std::size_t>(ch)];
      for (int k = kN - 1; k > i; --k) {
        s -= at(k, i) * b[static_cast<std::size_t>(k)][static_cast<std::size_t>(ch)];
      }
      b[static_cast<std::size_t>(i)][static_cast<std::size_t>(ch)] = s * at(i, i);
    }
  }
  return true;
}

}  // namespace

template <int kChannels>
FreeFit<kChannels> SolveFree(const RegionSystem<kChannels>& system) {
  FreeFit<kChannels> fit;
  if (system.samples == 0 || !(system.weight > 0)) return fit;
  double trace = 0;
  for (int a = 0; a < kN; ++a) {
    trace += system.at(a, a);
    fit.support[static_cast<std::size_t>(a)] = system.at(a, a);
  }
  // A little ridge towards the mean keeps regions the samples barely see from swinging.
  const double ridge = 0.01 * trace / kN;
  Square ridged = system.ata;
  for (int a = 0; a < kN; ++a) ridged[static_cast<std::size_t>(a) * kN + a] += ridge;
  // The samples' total weight: Σ Aᵀy over regions is Σ weight · y (coverage sums to one per
  // sample, kernels to one), so this gives the weighted mean whatever scale the weights have.
  const double n = system.weight;
  std::array<std::array<double, kChannels>, kN> x{};
  for (int ch = 0; ch < kChannels; ++ch) {
    const auto& aty = system.aty[static_cast<std::size_t>(ch)];
    double mean = 0;
    for (int a = 0; a < kN; ++a) mean += aty[static_cast<std::size_t>(a)];
    mean /= n;
    for (int a = 0; a < kN; ++a) {
      x[static_cast<std::size_t>(a)][static_cast<std::size_t>(ch)] =
          aty[static_cast<std::size_t>(a)] + ridge * mean;
    }
  }
  if (!SolveCholesky<kChannels>(ridged, x)) return fit;
  for (int ch = 0; ch < kChannels; ++ch) {
    const auto& aty = system.aty[static_cast<std::size_t>(ch)];
    double residual = system.yty[static_cast<std::size_t>(ch)];
    for (int a = 0; a < kN; ++a) {
      // (m x)(a), summed as cv::Matx's product sums it.
      double mx = 0;
      for (int k = 0; k < kN; ++k) {
        mx += system.at(a, k) * x[static_cast<std::size_t>(k)][static_cast<std::size_t>(ch)];
      }
      const double xa = x[static_cast<std::size_t>(a)][static_cast<std::size_t>(ch)];
      residual += xa * (mx - 2 * aty[static_cast<std::size_t>(a)]);
      fit.colour[static_cast<std::size_t>(ch)][static_cast<std::size_t>(a)] = xa;
    }
    fit.residual[static_cast<std::size_t>(ch)] = std::max(0.0, residual);
  }
  fit.ok = true;
  return fit;
}

template FreeFit<1> SolveFree<1>(const RegionSystem<1>&);
template FreeFit<2> SolveFree<2>(const RegionSystem<2>&);

}  // namespace pintag::reading
