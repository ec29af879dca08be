#include "redness.hpp"

#include <cmath>

#include "lab_approx.hpp"

namespace pintag::stage {
namespace {

struct ScaledThresholds {
  int a;
  int b;
};

ScaledThresholds Scale(const RednessThresholds& t) {
  return {static_cast<int>(std::lround(t.min_a * kLabScale)),
          static_cast<int>(std::lround(t.min_b * kLabScale))};
}

}  // namespace

bool IsRedLab(double a, double b, const RednessThresholds& thresholds) {
  return a >= thresholds.min_a && b >= thresholds.min_b;
}

bool IsRedPixel(int r, int g, int b, const RednessThresholds& thresholds) {
  if (r - g < kRednessPrefilter) return false;
  const ScaledThresholds s = Scale(thresholds);
  int a_star, b_star;
  LabApprox::Get().Ab(r, g, b, &a_star, &b_star);
  return a_star >= s.a && b_star >= s.b;
}

cv::Mat RednessMask(const cv::Mat& bgr, const RednessThresholds& thresholds) {
  CV_Assert(bgr.type() == CV_8UC3);
  cv::Mat mask(bgr.size(), CV_8U);
  const ScaledThresholds s = Scale(thresholds);
  const LabApprox& lab = LabApprox::Get();
  for (int y = 0; y < bgr.rows; ++y) {
    const std::uint8_t* p = bgr.ptr<std::uint8_t>(y);
    std::uint8_t* m = mask.ptr<std::uint8_t>(y);
    for (int x = 0; x < bgr.cols; ++x, p += 3) {
      const int r = p[2], g = p[1];
      std::uint8_t out = 0;
      if (r - g >= kRednessPrefilter) {
        int a_star, b_star;
        lab.Ab(r, g, p[0], &a_star, &b_star);
        out = (a_star >= s.a && b_star >= s.b) ? 255 : 0;
      }
      m[x] = out;
    }
  }
  return mask;
}

}  // namespace pintag::stage
