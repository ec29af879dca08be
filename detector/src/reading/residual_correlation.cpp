#include "reading/residual_correlation.hpp"

#include <algorithm>
#include <vector>

namespace pintag::reading {

ResidualCorrelation NeighbourCorrelation(std::span<const GridResidual> residuals,
                                         const cv::Rect& bounds, int step) {
  CV_Assert(step >= 1);
  if (bounds.width <= 0 || bounds.height <= 0) return {};
  // Each sample's grid cell, and the sample in each cell, so that a sample's right and lower
  // neighbours are found directly.
  const int cols = bounds.width / step + 1, rows = bounds.height / step + 1;
  std::vector<int> sample_at(static_cast<std::size_t>(cols) * static_cast<std::size_t>(rows), -1);
  std::vector<int> cell_of(residuals.size(), -1);
  for (std::size_t i = 0; i < residuals.size(); ++i) {
    const int gx = (residuals[i].x - bounds.x) / step, gy = (residuals[i].y - bounds.y) / step;
    if (gx < 0 || gy < 0 || gx >= cols || gy >= rows) continue;
    cell_of[i] = gy * cols + gx;
    sample_at[static_cast<std::size_t>(cell_of[i])] = static_cast<int>(i);
  }
  double cross_x = 0, square_x = 0, cross_y = 0, square_y = 0;
  const auto add = [](const GridResidual& a, const GridResidual& b, double* cross, double* square) {
    for (std::size_t k = 0; k < a.r.size(); ++k) {
      *cross += a.r[k] * b.r[k];
      *square += a.r[k] * a.r[k];
    }
  };
  for (std::size_t i = 0; i < residuals.size(); ++i) {
    const int cell = cell_of[i];
    if (cell < 0) continue;
    const int right = cell % cols + 1 < cols ? sample_at[static_cast<std::size_t>(cell) + 1] : -1;
    const int below =
        cell / cols + 1 < rows
            ? sample_at[static_cast<std::size_t>(cell) + static_cast<std::size_t>(cols)]
            : -1;
    if (right >= 0)
      add(residuals[i], residuals[static_cast<std::size_t>(right)], &cross_x, &square_x);
    if (below >= 0)
      add(residuals[i], residuals[static_cast<std::size_t>(below)], &cross_y, &square_y);
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
