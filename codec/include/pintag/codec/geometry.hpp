#pragma once
// Format-v1 geometry in tag units (DESIGN.md §2): the black square's side is 1, x right, y down,
// origin at the square's top-left corner; angles clockwise from up (−y).

#include <array>
#include <cmath>
#include <numbers>

#include "pintag/codec/cells.hpp"

namespace pintag::geometry {

struct Point {
  double x = 0;
  double y = 0;
};

inline constexpr double kQuietZone = 0.15;  ///< white margin on every side, part of every tag
inline constexpr double kRedRadius = 0.10;  ///< red disk
inline constexpr double kGreenOuterRadius = 0.20;  ///< green ring spans kRedRadius … this
inline constexpr std::array<Point, kElements> kElementCentres = {
    Point{0.25, 0.25}, Point{0.75, 0.25}, Point{0.75, 0.75}, Point{0.25, 0.75}};
/// The black square's corners, same order as the elements: C0 top-left, then clockwise.
inline constexpr std::array<Point, 4> kSquareCorners = {Point{0, 0}, Point{1, 0}, Point{1, 1},
                                                        Point{0, 1}};

/// Unit vector for an angle in degrees, clockwise from up.
inline Point Direction(double degrees) {
  const double radians = degrees * std::numbers::pi / 180.0;
  return {std::sin(radians), -std::cos(radians)};
}

/// Angle in degrees [0, 360) of the vector (dx, dy), clockwise from up.
inline double AngleOf(double dx, double dy) {
  const double degrees = std::atan2(dx, -dy) * 180.0 / std::numbers::pi;
  return degrees < 0 ? degrees + 360.0 : degrees;
}

/// Nominal centre of a green sector: mid-radius of the ring, mid-angle of the sector.
inline Point GreenSectorCentre(int element, int sector) {
  const Point c = kElementCentres[element];
  const Point d = Direction(45.0 * sector + 22.5);
  const double r = (kRedRadius + kGreenOuterRadius) / 2;
  return {c.x + r * d.x, c.y + r * d.y};
}

/// Nominal centre of a red quadrant: half the disk radius out, mid-angle of the quadrant.
inline Point RedQuadrantCentre(int element, int quadrant) {
  const Point c = kElementCentres[element];
  const Point d = Direction(90.0 * quadrant + 45.0);
  const double r = kRedRadius / 2;
  return {c.x + r * d.x, c.y + r * d.y};
}

enum class Region { kOutside, kBlack, kRed, kGreen };

/// Which cell a point of the tag lies in. `index` is the quadrant (kRed) or sector (kGreen).
struct CellAt {
  Region region = Region::kOutside;
  int element = -1;
  int index = -1;
};

/// Classifies a point given in tag units; everything outside the unit square is kOutside (quiet
/// zone).
CellAt LocateCell(double x, double y);

}  // namespace pintag::geometry
