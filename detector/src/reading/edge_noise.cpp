#include "reading/edge_noise.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace pintag::reading {

std::vector<double> SampleContrast(const LumaRows& rows,
                                   const std::array<double, kModelRegions>& colours) {
  std::vector<double> contrast;
  contrast.reserve(rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    // The variance of the colours under the sample, each by its taps' magnitude (a sharpening
    // kernel has negative ones): 0 inside one region.
    double total = 0, mean = 0, second = 0;
    for (const LumaRows::Term& t : rows.terms(i)) {
      const double a = std::abs(t.weight), c = colours[static_cast<std::size_t>(t.region)];
      total += a, mean += a * c, second += a * c * c;
    }
    if (total <= 0) {
      contrast.push_back(0);
      continue;
    }
    mean /= total;
    contrast.push_back(std::max(0.0, second / total - mean * mean));
  }
  return contrast;
}

EdgeNoise FitEdgeNoise(const LumaRows& rows, std::span<const double> contrast,
                       const std::array<double, kModelRegions>& colours) {
  assert(contrast.size() == rows.size());
  std::vector<double> squared;
  squared.reserve(rows.size());
  double mean_squared = 0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    double predicted = 0;
    for (const LumaRows::Term& t : rows.terms(i)) {
      predicted += t.weight * colours[static_cast<std::size_t>(t.region)];
    }
    const double r = rows.value(i) - predicted;
    squared.push_back(r * r);
    mean_squared += r * r / static_cast<double>(rows.size());
  }
  if (rows.size() < 2 || !(mean_squared > 0) || !std::isfinite(mean_squared)) return {};
  // A squared residual varies as its expected value squared, so a plain fit would let the few
  // samples on strong edges set the floor: least squares reweighted by the last fit's expected
  // value instead (the first pass unweighted). In units of the mean square, so that no scale of
  // the residuals overflows the weights.
  EdgeNoise unit;
  for (int pass = 0; pass < 4; ++pass) {
    double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (std::size_t i = 0; i < squared.size(); ++i) {
      const double x = std::max(0.0, contrast[i]), y = squared[i] / mean_squared;
      const double expected = unit.floor + unit.per_contrast * x;
      const double w = pass == 0 ? 1.0 : 1 / (expected * expected);
      n += w, sx += w * x, sy += w * y, sxx += w * x * x, sxy += w * x * y;
    }
    const double det = n * sxx - sx * sx;
    const double slope = det > 1e-12 * n * sxx ? std::max(0.0, (n * sxy - sx * sy) / det) : 0.0;
    unit.per_contrast = slope;
    unit.floor = std::max((sy - slope * sx) / n, 0.05);
  }
  const EdgeNoise noise{unit.floor * mean_squared, unit.per_contrast * mean_squared};
  if (!std::isfinite(noise.floor) || !std::isfinite(noise.per_contrast)) return {};
  return noise;
}

std::vector<double> EdgeNoiseWeights(const EdgeNoise& noise, std::span<const double> contrast) {
  std::vector<double> weights;
  if (!(noise.floor > 0)) return weights;
  weights.reserve(contrast.size());
  for (const double x : contrast)
    weights.push_back(noise.floor / (noise.floor + noise.per_contrast * x));
  return weights;
}

}  // namespace pintag::reading
