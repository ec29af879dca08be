#include "corner_fit.hpp"

#include <cmath>

#include "homography.hpp"

namespace pintag::stage {

CornerFit FitCornersThroughBlur(const cv::Mat& bgr, const Quad& quad, const BlurFit& fit) {
  CornerFit out;
  out.quad = quad;
  if (MeanSidePx(quad) > kCornerFitMaxSidePx) return out;
  // One pixel set for every trial (chosen by image position), so that residuals compare.
  const std::size_t stride = CornerSearchStride(std::abs(SignedArea2(quad)) / 2);
  const auto residual = [&](const Quad& q) {
    ++out.evaluations;
    return ResidualAtFittedBlur(bgr, HomographyFromQuad(q), fit, stride);
  };
  double best = residual(quad);
  out.residual_before = best;
  out.residual_after = best;
  if (!std::isfinite(best)) return out;
  constexpr int kMaxSweepsPerStep = 3;
  for (const double step : {0.4, 0.2, 0.1}) {
    for (int sweep = 0; sweep < kMaxSweepsPerStep; ++sweep) {
      bool improved = false;
      for (int corner = 0; corner < 4; ++corner) {
        for (int axis = 0; axis < 2; ++axis) {
          for (const double sign : {1.0, -1.0}) {
            Quad trial = out.quad;
            double& coordinate = axis == 0 ? trial[corner].x : trial[corner].y;
            coordinate += sign * step;
            if (cv::norm(trial[corner] - quad[corner]) > kCornerFitMaxMovePx) continue;
            const double r = residual(trial);
            if (!(r < best)) continue;  // also refuses a NaN
            best = r;
            out.quad = trial;
            improved = true;
            break;  // one direction per coordinate and sweep
          }
        }
      }
      if (!improved) break;
    }
  }
  out.residual_after = best;
  out.moved = best < out.residual_before;
  return out;
}

}  // namespace pintag::stage
