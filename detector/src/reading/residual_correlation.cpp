#include "reading/residual_correlation.hpp"

#include <algorithm>
#include <vector>

namespace pintag::reading {

ResidualCorrelation NeighbourCorrelation(std::span<const GridResidual> residuals,
                                         const cv::Rect& bounds, int step, int channels) {
  CV_Assert(step >= 1 && channels >= 1 && channels <= 2);
  // Each sample's index by grid cell, so that its right and lower neighbours are found directly.
  const int cols = bounds.width / step + 1, rows = bounds.height / step + 1;
  if (bounds.width <= 0 || bounds.height <= 0) return {};
  std::vector<int> index(static_cast<std::size_t>(cols) * static_cast<std::size_t>(rows), -1);
  const auto cell = [&](const GridResidual& g, int* gx, int* gy) {
    *gx = (g.x - bounds.x) / step;
    *gy = (g.y - bounds.y) / step;
    return *gx >= 0 && *gy >= 0 && *gx < cols && *gy < rows;
  };
  for (std::size_t i = 0; i < residuals.size(); ++i) {
    int gx = 0, gy = 0;
    if (cell(residuals[i], &gx, &gy)) {
      index[static_cast<std::size_t>(gy) * static_cast<std::size_t>(cols) +
            static_cast<std::size_t>(gx)] = static_cast<int>(i);
    }
  }
  double cross_x = 0, square_x = 0, cross_y = 0, square_y = 0;
  for (const GridResidual& g : residuals) {
    int gx = 0, gy = 0;
    if (!cell(g, &gx, &gy)) continue;
    const std::size_t at = static_cast<std::size_t>(gy) * static_cast<std::size_t>(cols) +
                           static_cast<std::size_t>(gx);
    const int right = gx + 1 < cols ? index[at + 1] : -1;
    const int below = gy + 1 < rows ? index[at + static_cast<std::size_t>(cols)] : -1;
    for (std::size_t k = 0; k < static_cast<std::size_t>(channels); ++k) {
      if (right >= 0) {
        cross_x += g.r[k] * residuals[static_cast<std::size_t>(right)].r[k];
        square_x += g.r[k] * g.r[k];
      }
      if (below >= 0) {
        cross_y += g.r[k] * residuals[static_cast<std::size_t>(below)].r[k];
        square_y += g.r[k] * g.r[k];
      }
    }
  }
  return {square_x > 0 ? cross_x / square_x : 0, square_y > 0 ? cross_y / square_y : 0};
}

double VarianceInflation(const ResidualCorrelation& correlation) {
  const auto factor = [](double rho) {
    rho = std::clamp(rho, 0.0, kMaxCountedCorrelation);
    return (1 + rho) / (1 - rho);
  };
  return factor(correlation.x) * factor(correlation.y);
}

}  // namespace pintag::reading
