#include "colour_content.hpp"

#include <algorithm>
#include <cstdint>

namespace pintag::stage {

bool HoldsColour(const cv::Mat& bgr) {
  constexpr int kMinSpread = 8;
  constexpr int kMinColouredSamples = 16;
  const std::int64_t samples = std::int64_t{(bgr.rows + 1) / 2} * ((bgr.cols + 1) / 2);
  const std::int64_t needed = std::max<std::int64_t>(kMinColouredSamples, samples / 10'000);
  std::int64_t coloured = 0;
  for (int y = 0; y < bgr.rows; y += 2) {
    const auto* p = bgr.ptr<std::uint8_t>(y);
    for (int x = 0; x < bgr.cols; x += 2, p += 6) {
      const int lo = std::min({p[0], p[1], p[2]});
      const int hi = std::max({p[0], p[1], p[2]});
      // Most colour photos are decided within their first rows.
      if (hi - lo >= kMinSpread && ++coloured >= needed) return true;
    }
  }
  return false;
}

}  // namespace pintag::stage
