#include "candidates/redness.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <utility>

#include "candidates/frame_scan.hpp"
#include "candidates/lab_approx.hpp"
#include "candidates/least_r_table.hpp"

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

RedTable::RedTable(const RednessThresholds& thresholds)
    : least_red_r_(
          LeastRTable([&](int r, int g, int b) { return IsRedPixel(r, g, b, thresholds); })) {
  // The lead grows with R, so each (G, B)'s least red R gives its least red lead.
  least_red_lead_ = 1 << 20;
  for (int g = 0; g < 256; ++g) {
    for (int b = 0; b < 256; ++b) {
      const int r = least_red_r_[static_cast<std::size_t>((g << 8) | b)];
      if (r < 256) least_red_lead_ = std::min(least_red_lead_, 4 * (r - g) + (b - g));
    }
  }
}

const RedTable& RedTable::For(const RednessThresholds& thresholds) {
  // Keyed by the thresholds as LabApprox compares them; detectors are built with few distinct ones.
  static std::mutex mutex;
  static std::map<std::pair<int, int>, std::unique_ptr<RedTable>> tables;
  const ScaledThresholds s = Scale(thresholds);
  const std::lock_guard<std::mutex> lock(mutex);
  std::unique_ptr<RedTable>& table = tables[{s.a, s.b}];
  if (!table) table.reset(new RedTable(thresholds));
  return *table;
}

RedRuns FindRedRuns(const cv::Mat& bgr, const RednessThresholds& thresholds) {
  FrameScanRequest request;
  request.red = thresholds;
  return ScanFrame(bgr, request).red;
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
