#include "pintag/codec/geometry.hpp"

namespace pintag::geometry {

CellAt LocateCell(double x, double y) {
  if (x < 0 || y < 0 || x >= 1 || y >= 1) return {};
  // Elements sit in the four quarters of the square; only the nearest can contain the point.
  const int column = x < 0.5 ? 0 : 1;
  const int row = y < 0.5 ? 0 : 1;
  const int element = row == 0 ? column : 3 - column;
  const Point c = kElementCentres[element];
  const double dx = x - c.x;
  const double dy = y - c.y;
  const double r2 = dx * dx + dy * dy;
  if (r2 >= kGreenOuterRadius * kGreenOuterRadius) return {Region::kBlack, -1, -1};
  const double angle = AngleOf(dx, dy);
  if (r2 < kRedRadius * kRedRadius) {
    return {Region::kRed, element, static_cast<int>(angle / 90.0) % kRedQuadrants};
  }
  return {Region::kGreen, element, static_cast<int>(angle / 45.0) % kGreenSectors};
}

}  // namespace pintag::geometry
