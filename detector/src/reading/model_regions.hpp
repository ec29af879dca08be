#pragma once
// The tag as the reading model sees it: 50 regions (the quiet zone, the black square, then per
// element its 4 red quadrants and 8 green sectors), the six colours a printed tag has, and the
// canonical order of the 48 cells in which codewords are bit masks.

#include <cstdint>
#include <vector>

#include "pintag/codec/cells.hpp"
#include "pintag/codec/geometry.hpp"

namespace pintag::reading {

inline constexpr int kCellsPerElement = kRedQuadrants + kGreenSectors;
inline constexpr int kModelRegions = 2 + kElements * kCellsPerElement;
inline constexpr int kQuietRegion = 0;
inline constexpr int kBlackRegion = 1;

inline constexpr int RedRegion(int element, int quadrant) {
  return 2 + element * kCellsPerElement + quadrant;
}
inline constexpr int GreenRegion(int element, int sector) {
  return 2 + element * kCellsPerElement + kRedQuadrants + sector;
}

/// The model region of a point in tag units: 0 outside the square, 1 black, then element e's red
/// quadrant q at RedRegion(e, q) and green sector s at GreenRegion(e, s) (geometry::LocateCell's
/// cells, found by comparisons instead of atan2: this runs for every sub-sample of a tag's pixels,
/// so it is inline).
inline int ModelRegionAt(double x, double y) {
  if (x < 0 || y < 0 || x >= 1 || y >= 1) return kQuietRegion;
  const int column = x < 0.5 ? 0 : 1, row = y < 0.5 ? 0 : 1;
  const int element = row == 0 ? column : 3 - column;
  const geometry::Point c = geometry::kElementCentres[element];
  const double right = x - c.x, up = c.y - y;  // clockwise angles from up
  const double r2 = right * right + up * up;
  constexpr double kOuter2 = geometry::kGreenOuterRadius * geometry::kGreenOuterRadius;
  constexpr double kRed2 = geometry::kRedRadius * geometry::kRedRadius;
  if (r2 >= kOuter2) return kBlackRegion;
  // Sector boundaries are the diagonals and axes, so comparisons of the offsets decide them.
  int sector;
  if (right >= 0) {
    sector = up > 0 ? (right < up ? 0 : 1) : (right > -up ? 2 : 3);
  } else {
    sector = up < 0 ? (-right < -up ? 4 : 5) : (-right > up ? 6 : 7);
  }
  return r2 < kRed2 ? RedRegion(element, sector / 2) : GreenRegion(element, sector);
}

/// The six colours of a printed tag, the levels a region can take.
enum Level : std::uint8_t { kQuietLevel, kBlackLevel, kRed0, kRed1, kGreen0, kGreen1, kLevels };

inline constexpr int Flipped(int level) {
  return level == kRed0 ? kRed1 : level == kRed1 ? kRed0 : level == kGreen0 ? kGreen1 : kGreen0;
}
inline constexpr bool IsOneLevel(int level) {
  return level == kRed1 || level == kGreen1;
}

/// Canonical cells: green (e, s) at 8 e + s, red (e, q) at 32 + 4 e + q, as the codec's
/// orientation has them.
inline constexpr int kCanonicalCells = kElements * kCellsPerElement;
static_assert(kCanonicalCells == 48);

/// The region of canonical cell `canonical` when element `quarter_turns` of the sampled frame is
/// C0.
int SampledRegion(int canonical, int quarter_turns);

/// Every key's 48 cells as a bit mask in canonical order (bit c set: cell c is a one), built once.
const std::vector<std::uint64_t>& Codebook();

/// The keys d ≠ 0 whose codeword differs from key 0's in at most `kNeighbourCells` cells,
/// ascending. The code is affine (both payload copies and the parity are sums of key bits, the
/// orientation cells constant), so key c's and key c ⊕ d's codewords differ in exactly the cells
/// key 0's and key d's do: the codewords within that many cells of key c's are those of c ⊕ d.
inline constexpr int kNeighbourCells = 7;
const std::vector<int>& NeighbourKeyOffsets();

}  // namespace pintag::reading
