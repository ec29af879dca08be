#include "candidates/least_r_table.hpp"

namespace pintag::stage {

std::vector<std::uint16_t> LeastRTable(const std::function<bool(int r, int g, int b)>& holds) {
  std::vector<std::uint16_t> least(std::size_t{256} * 256);
  for (int g = 0; g < 256; ++g) {
    for (int b = 0; b < 256; ++b) {
      int lo = 0, hi = 256;
      while (lo < hi) {
        const int mid = (lo + hi) / 2;
        if (holds(mid, g, b)) {
          hi = mid;
        } else {
          lo = mid + 1;
        }
      }
      least[static_cast<std::size_t>((g << 8) | b)] = static_cast<std::uint16_t>(lo);
    }
  }
  return least;
}

}  // namespace pintag::stage
