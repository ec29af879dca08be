#include "reading/model_regions.hpp"

#include <bit>

#include "pintag/codec/geometry.hpp"

namespace pintag::reading {

// Sector boundaries are the diagonals and axes, so comparisons of the offsets decide them.
int ModelRegionAt(double x, double y) {
  if (x < 0 || y < 0 || x >= 1 || y >= 1) return kQuietRegion;
  const int column = x < 0.5 ? 0 : 1, row = y < 0.5 ? 0 : 1;
  const int element = row == 0 ? column : 3 - column;
  const geometry::Point c = geometry::kElementCentres[element];
  const double right = x - c.x, up = c.y - y;  // clockwise angles from up
  const double r2 = right * right + up * up;
  constexpr double kOuter2 = geometry::kGreenOuterRadius * geometry::kGreenOuterRadius;
  constexpr double kRed2 = geometry::kRedRadius * geometry::kRedRadius;
  if (r2 >= kOuter2) return kBlackRegion;
  int sector;
  if (right >= 0) {
    sector = up > 0 ? (right < up ? 0 : 1) : (right > -up ? 2 : 3);
  } else {
    sector = up < 0 ? (-right < -up ? 4 : 5) : (-right > up ? 6 : 7);
  }
  return r2 < kRed2 ? RedRegion(element, sector / 2) : GreenRegion(element, sector);
}

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
