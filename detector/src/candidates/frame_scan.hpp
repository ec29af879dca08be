#pragma once
// Stage 1, the one pass over the whole frame. Reading 6 MB of pixels costs more than the little
// work done on each, so everything the later stages need from every pixel is taken in the same
// pass: the red runs at the main threshold and at the faint pass's, the image of min(R, G, B) in
// which a tag, its elements included, is one dark square inside its white quiet zone (stage 3a
// looks for that square around each blob cluster), and the same at half resolution (stage 3e's
// candidates without red).

#include <opencv2/core.hpp>
#include <optional>

#include "candidates/redness.hpp"

namespace pintag::stage {

/// How the red tables are read. The results are the same; kFastest gathers 16 entries at a time
/// with AVX2 where the CPU has it (checked at run time: the build targets plain x86-64).
enum class RedLookups {
  kFastest,
  kOneByOne,  ///< one table read per pixel, on every CPU (tests compare the two)
};

/// Whether kFastest gathers on this CPU.
bool GathersRedLookups();

struct FrameScanRequest {
  RednessThresholds red;                   ///< the main pass
  std::optional<RednessThresholds> faint;  ///< the faint pass; none: not scanned
  bool min_channel = false;                ///< also keep FrameScan::min_channel
  bool dark_half = false;                  ///< also build FrameScan::dark_half
  RedLookups lookups = RedLookups::kFastest;
};

struct FrameScan {
  RedRuns red;    ///< exactly FindRedRuns(bgr, request.red)
  RedRuns faint;  ///< exactly FindRedRuns(bgr, *request.faint); empty when not asked for
  /// CV_8U, frame-sized: min(R, G, B) of every pixel (MinChannel of the whole frame); empty when
  /// not asked for.
  cv::Mat min_channel;
  /// CV_8U, (cols / 2) × (rows / 2): pixel (x, y) is the mean of min(R, G, B) over the 2 × 2
  /// block at (2x, 2y), rounded down; empty when not asked for.
  cv::Mat dark_half;
};

/// One pass over `bgr` (CV_8UC3).
FrameScan ScanFrame(const cv::Mat& bgr, const FrameScanRequest& request);

}  // namespace pintag::stage
