#pragma once
// The tag's 50 regions laid on the pixel grid through a homography: for every pixel of a box, the
// fraction of its area each region covers (4 × 4 sub-samples where a pixel holds more than one).

#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "reading/model_regions.hpp"
#include "reading/psf.hpp"

namespace pintag::reading {

/// Region weights of one sample, and which regions have any (for sparse sums).
struct SampleWeights {
  std::array<double, kModelRegions> weight{};
  std::array<bool, kModelRegions> listed{};
  std::vector<int> touched;
  void clear() {
    for (const int r : touched) {
      weight[static_cast<std::size_t>(r)] = 0;
      listed[static_cast<std::size_t>(r)] = false;
    }
    touched.clear();
  }
};

class RegionCoverage {
 public:
  /// Coverage of the pixels of `box` (image pixels) by the regions of the tag `tag_to_image` maps.
  RegionCoverage(const cv::Matx33d& tag_to_image, cv::Rect box);

  /// Adds to `out` the blurred coverage of the sample anchored at image pixel (x, y): Σ over the
  /// kernel's taps of tap weight × the coverage of the pixel under the tap. The kernel's reach
  /// must lie inside the box.
  void blurred(const Kernel& kernel, int x, int y, SampleWeights& out) const;

  const cv::Rect& box() const { return box_; }

 private:
  struct Part {
    int region;
    float weight;
  };
  struct Coverage {
    std::uint32_t first = 0;  // into parts_
    std::uint32_t count = 0;
  };
  // A pixel wholly in one region, and how many pixels from it rightwards are (length 0: several).
  struct RegionRun {
    std::uint8_t region = 0;
    std::uint8_t length = 0;
  };
  static_assert(kModelRegions <= 256);
  std::size_t index(int gx, int gy) const {
    return static_cast<std::size_t>(gy) * static_cast<std::size_t>(box_.width) +
           static_cast<std::size_t>(gx);
  }

  cv::Rect box_;
  std::vector<Coverage> coverage_;
  std::vector<Part> parts_;
  std::vector<RegionRun> runs_;
};

}  // namespace pintag::reading
