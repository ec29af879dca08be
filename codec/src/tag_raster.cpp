#include "pintag/codec/tag_raster.hpp"

#include <array>
#include <cmath>

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
  TagRaster raster{RgbImage(side, side), margin, n};
  const double inv_ss = 1.0 / ss;
  const double weight = 1.0 / (ss * ss);
  for (int py = 0; py < side; ++py) {
    for (int px = 0; px < side; ++px) {
      // Pixels wholly in the quiet zone are white; skip the sampling there.
      if (px < margin - 1 || py < margin - 1 || px > margin + n || py > margin + n) continue;
      Linear sum;
      for (int sy = 0; sy < ss; ++sy) {
        const double v = (py - margin + (sy + 0.5) * inv_ss) / n;
        for (int sx = 0; sx < ss; ++sx) {
          const double u = (px - margin + (sx + 0.5) * inv_ss) / n;
          const Linear& c = linear[static_cast<int>(ColourOf(geometry::LocateCell(u, v), cells))];
          sum.r += c.r;
          sum.g += c.g;
          sum.b += c.b;
        }
      }
      raster.image.set(px, py,
                       {LinearToSrgb(sum.r * weight), LinearToSrgb(sum.g * weight),
                        LinearToSrgb(sum.b * weight)});
    }
  }
  return raster;
}

}  // namespace pintag
