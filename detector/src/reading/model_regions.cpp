#include "reading/model_regions.hpp"

#include <bit>

namespace pintag::reading {

int SampledRegion(int canonical, int quarter_turns) {
  const int r = quarter_turns;
  if (canonical < 32) {
    const int e = canonical / 8, s = canonical % 8;
    return GreenRegion((e + r) % kElements, (s + 2 * r) % kGreenSectors);
  }
  const int e = (canonical - 32) / 4, q = (canonical - 32) % 4;
  return RedRegion((e + r) % kElements, (q + r) % kRedQuadrants);
}

const std::vector<std::uint64_t>& Codebook() {
  static const std::vector<std::uint64_t> book = [] {
    std::vector<std::uint64_t> b(kKeyCount);
    for (int k = 0; k < kKeyCount; ++k) {
      const TagCells cells = EncodeCells(TagKey(static_cast<std::uint16_t>(k)));
      std::uint64_t mask = 0;
      for (int e = 0; e < kElements; ++e) {
        for (int g = 0; g < kGreenSectors; ++g) {
          if (cells.green[e][g]) mask |= std::uint64_t{1} << (8 * e + g);
        }
        for (int q = 0; q < kRedQuadrants; ++q) {
          if (cells.red[e][q]) mask |= std::uint64_t{1} << (32 + 4 * e + q);
        }
      }
      b[static_cast<std::size_t>(k)] = mask;
    }
    return b;
  }();
  return book;
}

const std::vector<int>& NeighbourKeyOffsets() {
  static const std::vector<int> offsets = [] {
    const std::vector<std::uint64_t>& book = Codebook();
    std::vector<int> d;
    for (int k = 1; k < kKeyCount; ++k) {
      if (std::popcount(book[static_cast<std::size_t>(k)] ^ book[0]) <= kNeighbourCells) {
        d.push_back(k);
      }
    }
    return d;
  }();
  return offsets;
}

}  // namespace pintag::reading
