#pragma once
// How far a luma sample may stray from the model grows with the contrast under it. Where a
// sample straddles a bright and a dark region, a tenth of a pixel of corner error, a blur or
// sharpening the model does not quite have, or the demosaic's fringes move it by a share of that
// contrast; a sample inside one region moves only by noise. Measured on the tuning world, most of
// a small tag's residual is such model error at edges (docs/DETECTOR.md, "Luma samples weighted by
// the contrast they straddle"). Weighting each sample by the inverse of its expected residual
// variance lets the samples inside regions, which carry the colours, decide.

#include <array>
#include <span>
#include <vector>

#include "reading/model_regions.hpp"
#include "reading/region_system.hpp"

namespace pintag::reading {

/// Expected squared residual of a sample: `floor` + `per_contrast` × its contrast, the spread of
/// the region colours it straddles, weighted by their blurred coverage (luminance², 0 … 1).
struct EdgeNoise {
  double floor = 0;
  double per_contrast = 0;
};

/// Each sample's contrast under region colours `colours`.
std::vector<double> SampleContrast(const LumaRows& rows,
                                   const std::array<double, kModelRegions>& colours);

/// The edge noise fitted by least squares to the samples' squared residuals under `colours`
/// (`contrast`: SampleContrast of the same rows and colours, one per row). The floor is kept at
/// least 5 % of the mean squared residual, and per_contrast at least 0, so that no sample weighs
/// more than a sample inside one region. All zero when the samples fit exactly.
EdgeNoise FitEdgeNoise(const LumaRows& rows, std::span<const double> contrast,
                       const std::array<double, kModelRegions>& colours);

/// Each sample's weight, floor / its expected squared residual: 1 inside a region, less across
/// edges. Empty (every sample weighs 1) when `noise` has no floor.
std::vector<double> EdgeNoiseWeights(const EdgeNoise& noise, std::span<const double> contrast);

}  // namespace pintag::reading
