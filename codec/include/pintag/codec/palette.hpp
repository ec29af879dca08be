#pragma once
// The five printed colours of format v1 plus the quiet zone's white (DESIGN.md §2), in one place.

#include <array>
#include <string_view>

#include "pintag/codec/cielab.hpp"

namespace pintag {

enum class PaletteColour { kRedOne, kRedZero, kGreenOne, kGreenZero, kBlack, kWhite };

struct PaletteEntry {
  PaletteColour colour;
  std::string_view name;
  Lab target;  ///< CIELAB (D65) target of DESIGN.md §2
  Rgb8 srgb;   ///< the sRGB value printed and rendered
};

// The sRGB values are the targets converted exactly and rounded; teal sits a hair outside the
// gamut (linear red −0.0003) and is clamped, which moves it by less than ΔE 0.5.
inline constexpr std::array<PaletteEntry, 6> kPalette = {{
    {PaletteColour::kRedOne, "red bit 1 (orange-red)", {58, 62, 68}, {249, 80, 3}},
    {PaletteColour::kRedZero, "red bit 0 (crimson)", {45, 72, -8}, {204, 13, 122}},
    {PaletteColour::kGreenOne, "green bit 1 (yellow-green)", {72, -42, 66}, {132, 194, 36}},
    {PaletteColour::kGreenZero, "green bit 0 (teal)", {58, -35, -7}, {0, 156, 151}},
    {PaletteColour::kBlack, "black square", {10, 0, 0}, {27, 27, 27}},
    {PaletteColour::kWhite, "quiet zone white", {100, 0, 0}, {255, 255, 255}},
}};

constexpr const PaletteEntry& PaletteFor(PaletteColour colour) {
  return kPalette[static_cast<int>(colour)];
}

constexpr Rgb8 SrgbFor(PaletteColour colour) {
  return PaletteFor(colour).srgb;
}

}  // namespace pintag
