#pragma once
// How much neighbouring residuals of a fit move together. A codeword's lead is counted in noise
// units as if every sample's residual were independent; where blur (motion blur above all) or a
// misfit makes neighbours' residuals alike, fewer independent samples stand behind the same lead,
// and a wrong codeword can lead by a hundred units. Dividing the lead by the inflation below
// counts it in independent samples instead (docs/DETECTOR.md, "The lead in independent samples").

#include <array>
#include <opencv2/core.hpp>
#include <span>

namespace pintag::reading {

/// One sample's residual, per channel (a single-channel fit leaves the second 0), at its grid
/// position.
struct GridResidual {
  int x = 0, y = 0;  ///< image pixel (the sample grid's step apart)
  std::array<double, 2> r{};
};

/// Lag-1 correlation along x and along y: Σ r·r' / Σ r² over every pair of neighbours one
/// grid step apart, the channels pooled.
struct ResidualCorrelation {
  double x = 0;
  double y = 0;
};

/// `residuals` lie on a grid `step` px apart inside `bounds`. Samples with no neighbour in a
/// direction add nothing to it; no pairs give 0.
ResidualCorrelation NeighbourCorrelation(std::span<const GridResidual> residuals,
                                         const cv::Rect& bounds, int step);

/// Least and most correlation counted (a negative one is taken as none; near 1 the factor grows
/// without bound and one channel would decide alone).
inline constexpr double kMaxCountedCorrelation = 0.9;

/// How many times a sum over correlated residuals varies more than one over independent ones, for
/// residuals correlated as a separable first-order process: Π over x and y of (1 + ρ) / (1 − ρ),
/// ρ clamped to [0, kMaxCountedCorrelation]. 1 for independent residuals.
double VarianceInflation(const ResidualCorrelation& correlation);

}  // namespace pintag::reading
