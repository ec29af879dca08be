#pragma once
// Stage 1, redness: which pixels are the tag's red (CIELAB a* >= red_min_a and b* >= red_min_b).
//
// A whole-frame float CIELAB conversion costs ~5 ms at 1080p, and even the integer LabApprox on
// the pixels that pass a cheap R − G pre-check cost ~4 ms, since warm photographs pass it nearly
// everywhere. Instead, for every (G, B) the least R that makes a pixel red is tabulated once per
// threshold pair (the red set is upward-closed in R: a* and b* both grow with R), and the pass is
// one table lookup and one comparison per pixel (frame_scan.cpp gathers 16 pixels' entries at once
// where the CPU has AVX2). A test proves over the whole sRGB cube that the table and LabApprox
// agree on every colour.

#include <cstdint>
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

/// The redness rule as a table: `isRed(r, g, b)` is exactly `IsRedPixel(r, g, b, thresholds)`.
class RedTable {
 public:
  /// Built on first use for each threshold pair (a few ms) and kept for the process.
  static const RedTable& For(const RednessThresholds& thresholds);

  bool isRed(int r, int g, int b) const { return r >= least_red_r_[(g << 8) | b]; }

  /// The least 4 (R − G) + (B − G) of any red colour (a large number when none is): a pixel below
  /// it is not red, which a frame scan can test on many pixels at once before looking any up.
  int leastRedLead() const { return least_red_lead_; }

  /// The table itself, 65,536 entries: the least red R (256: none) at index (G << 8) | B.
  const std::uint16_t* leastRedR() const { return least_red_r_.data(); }

 private:
  explicit RedTable(const RednessThresholds& thresholds);
  std::vector<std::uint16_t> least_red_r_;  // least red R (256: none), by (G << 8) | B
  int least_red_lead_ = 0;
};

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

/// One pass over `bgr` (CV_8UC3); the detector takes these from ScanFrame (frame_scan.hpp) with
/// its other full-frame work.
RedRuns FindRedRuns(const cv::Mat& bgr, const RednessThresholds& thresholds);

/// CV_8U mask: 255 where red, 0 elsewhere (tests and debug images).
cv::Mat RunsToMask(const RedRuns& runs);
cv::Mat RednessMask(const cv::Mat& bgr, const RednessThresholds& thresholds);

}  // namespace pintag::stage
