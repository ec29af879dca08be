#include "pintag/codec/tag_raster.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <vector>

#include "pintag/codec/cells.hpp"
#include "pintag/codec/geometry.hpp"
#include "pintag/codec/palette.hpp"

namespace pintag {
namespace {

struct Linear {
  double r = 0;
  double g = 0;
  double b = 0;
};

Linear ToLinear(Rgb8 c) {
  return {SrgbToLinear(c.r), SrgbToLinear(c.g), SrgbToLinear(c.b)};
}

PaletteColour ColourOf(const geometry::CellAt& cell, const TagCells& cells) {
  switch (cell.region) {
    case geometry::Region::kOutside:
      return PaletteColour::kWhite;
    case geometry::Region::kBlack:
      return PaletteColour::kBlack;
    case geometry::Region::kRed:
      return cells.red[cell.element][cell.index] ? PaletteColour::kRedOne : PaletteColour::kRedZero;
    case geometry::Region::kGreen:
      return cells.green[cell.element][cell.index] ? PaletteColour::kGreenOne
                                                   : PaletteColour::kGreenZero;
  }
  return PaletteColour::kWhite;
}

/// geometry::LocateCell without its atan2, which was most of a tag's rendering time: the eighth
/// of the circle from the signs of (dx, up) and which of the two is larger. The regions come from
/// the same expressions; within 1e-9 of a sector boundary (where the two could disagree by a
/// rounding) it asks LocateCell itself, so the answer is LocateCell's everywhere.
geometry::CellAt LocateCellQuickly(double x, double y) {
  if (x < 0 || y < 0 || x >= 1 || y >= 1) return {};
  const int column = x < 0.5 ? 0 : 1;
  const int row = y < 0.5 ? 0 : 1;
  const int element = row == 0 ? column : 3 - column;
  const geometry::Point c = geometry::kElementCentres[element];
  const double dx = x - c.x;
  const double dy = y - c.y;
  const double r2 = dx * dx + dy * dy;
  if (r2 >= geometry::kGreenOuterRadius * geometry::kGreenOuterRadius) {
    return {geometry::Region::kBlack, -1, -1};
  }
  const double up = -dy;
  constexpr double kTie = 1e-9;
  if (std::abs(dx) < kTie || std::abs(up) < kTie || std::abs(std::abs(dx) - std::abs(up)) < kTie) {
    return geometry::LocateCell(x, y);
  }
  // Quadrant clockwise from up, then the vector turned back into the first quadrant, where the
  // angle is past 45 degrees when its right component exceeds its up component.
  int quadrant = 0;
  double right = dx;
  double upward = up;
  if (dx > 0 && up < 0) {
    quadrant = 1, right = -up, upward = dx;
  } else if (dx < 0 && up < 0) {
    quadrant = 2, right = -dx, upward = -up;
  } else if (dx < 0 && up > 0) {
    quadrant = 3, right = up, upward = -dx;
  }
  if (r2 < geometry::kRedRadius * geometry::kRedRadius) {
    return {geometry::Region::kRed, element, quadrant};
  }
  return {geometry::Region::kGreen, element, 2 * quadrant + (right > upward ? 1 : 0)};
}

}  // namespace

int QuietZonePx(int square_px) {
  return static_cast<int>(std::ceil(geometry::kQuietZone * square_px - 1e-9));
}

TagRaster RenderTagRaster(TagKey key, const TagRasterOptions& options) {
  const TagCells cells = EncodeCells(key);
  const int n = options.square_px;
  const int margin = QuietZonePx(n);
  const int side = n + 2 * margin;
  const int ss = options.supersample < 1 ? 1 : options.supersample;

  std::array<Linear, kPalette.size()> linear{};
  for (std::size_t i = 0; i < kPalette.size(); ++i) linear[i] = ToLinear(kPalette[i].srgb);

  // Coverage is averaged in linear light, as a camera integrates it over a pixel.
  const double inv_ss = 1.0 / ss;
  const double weight = 1.0 / (ss * ss);
  const auto average = [&](const Linear& sum) {
    return Rgb8{LinearToSrgb(sum.r * weight), LinearToSrgb(sum.g * weight),
                LinearToSrgb(sum.b * weight)};
  };
  // A pixel wholly inside one cell gets that cell's colour as the supersampling would compute it
  // (the same sum, in the same order), so skipping the samples changes no pixel.
  std::array<Rgb8, kPalette.size()> uniform{};
  for (std::size_t i = 0; i < kPalette.size(); ++i) {
    Linear sum;
    for (int k = 0; k < ss * ss; ++k) {
      sum.r += linear[i].r;
      sum.g += linear[i].g;
      sum.b += linear[i].b;
    }
    uniform[i] = average(sum);
  }

  // The cell at every pixel corner, two grid rows at a time. A pixel whose four corners lie in the
  // same cell is inside it: cell boundaries are straight lines (square edges, sector rays, which
  // meet only at an element's centre, where the corners fall in four different quadrants) and
  // circles of radius at least 0.1 × kMinTagSquarePx = 6.4 px, which bulge at most 1/(8 × 6.4)
  // = 0.02 px into a pixel between its corners, short of the nearest sub-sample (1/(2 × ss) px
  // in). Only pixels on a boundary, a few percent of the tag, are supersampled.
  // Only grid points within an element's bounding box need classifying: the rest of the square is
  // black and the rest of the image quiet zone (LocateCell says the same there: a point at least
  // the ring's radius from the element centre along x or y is outside the ring).
  const auto fill_corner_row = [&](std::vector<geometry::CellAt>& row, int gy, int from, int to) {
    const double v = static_cast<double>(gy - margin) / n;
    const bool in_square_rows = v >= 0 && v < 1;
    for (int gx = from; gx <= to; ++gx) {
      const double u = static_cast<double>(gx - margin) / n;
      row[gx] = in_square_rows && u >= 0 && u < 1
                    ? geometry::CellAt{geometry::Region::kBlack, -1, -1}
                    : geometry::CellAt{};
    }
    if (!in_square_rows) return;
    const double cy = v < 0.5 ? geometry::kElementCentres[0].y : geometry::kElementCentres[3].y;
    if (std::abs(v - cy) >= geometry::kGreenOuterRadius) return;
    for (const double cx : {geometry::kElementCentres[0].x, geometry::kElementCentres[1].x}) {
      const int lo = std::max(
          from, static_cast<int>(std::floor((cx - geometry::kGreenOuterRadius) * n)) + margin);
      const int hi = std::min(
          to, static_cast<int>(std::ceil((cx + geometry::kGreenOuterRadius) * n)) + margin);
      for (int gx = lo; gx <= hi; ++gx) {
        row[gx] = LocateCellQuickly(static_cast<double>(gx - margin) / n, v);
      }
    }
  };
  const auto same = [](const geometry::CellAt& a, const geometry::CellAt& b) {
    return a.region == b.region && a.element == b.element && a.index == b.index;
  };
  // Pixels wholly in the quiet zone are white, as the image starts: only [first, last] is drawn.
  const int first = std::max(0, margin - 1);
  const int last = std::min(side - 1, margin + n);
  std::vector<geometry::CellAt> top(static_cast<std::size_t>(side) + 1);
  std::vector<geometry::CellAt> bottom(top.size());
  fill_corner_row(top, first, first, last + 1);

  TagRaster raster{RgbImage(side, side), margin, n};
  for (int py = first; py <= last; ++py) {
    fill_corner_row(bottom, py + 1, first, last + 1);
    for (int px = first; px <= last; ++px) {
      const geometry::CellAt& cell = top[px];
      if (same(cell, top[px + 1]) && same(cell, bottom[px]) && same(cell, bottom[px + 1])) {
        raster.image.set(px, py, uniform[static_cast<int>(ColourOf(cell, cells))]);
        continue;
      }
      Linear sum;
      for (int sy = 0; sy < ss; ++sy) {
        const double v = (py - margin + (sy + 0.5) * inv_ss) / n;
        for (int sx = 0; sx < ss; ++sx) {
          const double u = (px - margin + (sx + 0.5) * inv_ss) / n;
          const Linear& c = linear[static_cast<int>(ColourOf(LocateCellQuickly(u, v), cells))];
          sum.r += c.r;
          sum.g += c.g;
          sum.b += c.b;
        }
      }
      raster.image.set(px, py, average(sum));
    }
    std::swap(top, bottom);
  }
  return raster;
}

}  // namespace pintag
