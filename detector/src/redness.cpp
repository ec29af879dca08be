#include "redness.hpp"

#include <algorithm>
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
  LabApprox::Get().abStar(r, g, b, &a_star, &b_star);
  return a_star >= s.a && b_star >= s.b;
}

RedRuns FindRedRuns(const cv::Mat& bgr, const RednessThresholds& thresholds) {
  CV_Assert(bgr.type() == CV_8UC3);
  RedRuns out;
  out.size = bgr.size();
  const ScaledThresholds s = Scale(thresholds);
  const LabApprox& lab = LabApprox::Get();
  for (int y = 0; y < bgr.rows; ++y) {
    const std::uint8_t* row = bgr.ptr<std::uint8_t>(y);
    int start = -1;
    for (int x = 0; x < bgr.cols; ++x) {
      const std::uint8_t* p = row + 3 * static_cast<std::ptrdiff_t>(x);
      bool red = false;
      // Nearly every pixel stops at this integer comparison.
      if (p[2] >= p[1] + kRednessPrefilter) {
        int a_star, b_star;
        lab.abStar(p[2], p[1], p[0], &a_star, &b_star);
        red = a_star >= s.a && b_star >= s.b;
      }
      if (red && start < 0) start = x;
      if (!red && start >= 0) {
        out.runs.push_back({y, start, x - 1});
        start = -1;
      }
    }
    if (start >= 0) out.runs.push_back({y, start, bgr.cols - 1});
  }
  return out;
}

cv::Mat RunsToMask(const RedRuns& runs) {
  cv::Mat mask(runs.size, CV_8U, cv::Scalar(0));
  for (const RedRun& r : runs.runs) {
    std::uint8_t* row = mask.ptr<std::uint8_t>(r.y);
    std::fill(row + r.x0, row + r.x1 + 1, std::uint8_t{255});
  }
  return mask;
}

cv::Mat RednessMask(const cv::Mat& bgr, const RednessThresholds& thresholds) {
  return RunsToMask(FindRedRuns(bgr, thresholds));
}

}  // namespace pintag::stage
