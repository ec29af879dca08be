#pragma once
// Stage 1, redness: which pixels are the tag's red (CIELAB a* >= red_min_a and b* >= red_min_b).
//
// A whole-frame float CIELAB conversion costs ~5 ms at 1080p. Instead, one integer pass rejects
// every pixel whose R − G is below kRednessPrefilter (a test proves, over the sRGB cube, that no
// colour meeting the red condition is rejected), and the integer LabApprox is evaluated only on the
// few pixels that remain.

#include <opencv2/core.hpp>
#include <vector>

namespace pintag::stage {

inline constexpr int kRednessPrefilter = 2;  ///< least R − G (8-bit codes) of any red pixel

struct RednessThresholds {
  double min_a = 20;   ///< CIELAB a*
  double min_b = -30;  ///< CIELAB b*
};

/// The exact rule the stand-in implements, on an exact CIELAB value: used by tests.
bool IsRedLab(double a, double b, const RednessThresholds& thresholds);

/// The stand-in for one sRGB pixel.
bool IsRedPixel(int r, int g, int b, const RednessThresholds& thresholds);

/// A horizontal run of red pixels [x0, x1] on row y.
struct RedRun {
  int y;
  int x0;
  int x1;
};

/// The red pixels of a frame as runs, row by row (rows ascending, runs left to right). Red is
/// sparse in photos, so later stages work on runs rather than on a full-frame image.
struct RedRuns {
  cv::Size size;
  std::vector<RedRun> runs;
};

/// One pass over `bgr` (CV_8UC3).
RedRuns FindRedRuns(const cv::Mat& bgr, const RednessThresholds& thresholds);

/// CV_8U mask: 255 where red, 0 elsewhere (tests and debug images).
cv::Mat RunsToMask(const RedRuns& runs);
cv::Mat RednessMask(const cv::Mat& bgr, const RednessThresholds& thresholds);

}  // namespace pintag::stage
