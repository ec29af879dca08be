// The exact CIELAB conversion against published reference values, and the palette against the
// CIELAB targets of DESIGN.md §2.

#include <gtest/gtest.h>

#include "pintag/codec/cielab.hpp"
#include "pintag/codec/palette.hpp"

namespace pintag {
namespace {

void ExpectLabNear(Lab actual, Lab expected, double tolerance) {
  EXPECT_NEAR(actual.l, expected.l, tolerance);
  EXPECT_NEAR(actual.a, expected.a, tolerance);
  EXPECT_NEAR(actual.b, expected.b, tolerance);
}

TEST(Cielab, MatchesPublishedSrgbPrimaries) {
  // Widely published D65 values for the sRGB primaries and white.
  ExpectLabNear(SrgbToLab({255, 255, 255}), {100.0, 0.0, 0.0}, 0.01);
  ExpectLabNear(SrgbToLab({0, 0, 0}), {0.0, 0.0, 0.0}, 0.01);
  ExpectLabNear(SrgbToLab({255, 0, 0}), {53.24, 80.09, 67.20}, 0.05);
  ExpectLabNear(SrgbToLab({0, 255, 0}), {87.73, -86.18, 83.18}, 0.05);
  ExpectLabNear(SrgbToLab({0, 0, 255}), {32.30, 79.19, -107.86}, 0.05);
  ExpectLabNear(SrgbToLab({128, 128, 128}), {53.59, 0.0, 0.0}, 0.05);
}

TEST(Cielab, RoundTripsThroughLab) {
  for (int r = 0; r < 256; r += 15) {
    for (int g = 0; g < 256; g += 15) {
      for (int b = 0; b < 256; b += 15) {
        const Rgb8 colour{static_cast<std::uint8_t>(r), static_cast<std::uint8_t>(g),
                          static_cast<std::uint8_t>(b)};
        EXPECT_EQ(LabToSrgb(SrgbToLab(colour)), colour);
      }
    }
  }
}

TEST(Palette, EveryColourIsWithinDeltaE3OfItsTarget) {
  for (const PaletteEntry& entry : kPalette) {
    EXPECT_LT(DeltaE76(SrgbToLab(entry.srgb), entry.target), 3.0) << entry.name;
  }
}

TEST(Palette, ChannelsSeparateAsTheDesignSays) {
  // Red is found in a* (above +60; everything else below +5), bits are read in b*, the square in
  // L*.
  for (const PaletteEntry& entry : kPalette) {
    const Lab lab = SrgbToLab(entry.srgb);
    const bool red =
        entry.colour == PaletteColour::kRedOne || entry.colour == PaletteColour::kRedZero;
    if (red) {
      EXPECT_GT(lab.a, 60) << entry.name;
    } else {
      EXPECT_LT(lab.a, 5) << entry.name;
    }
  }
  EXPECT_GT(SrgbToLab(SrgbFor(PaletteColour::kRedOne)).b,
            SrgbToLab(SrgbFor(PaletteColour::kRedZero)).b + 60);
  EXPECT_GT(SrgbToLab(SrgbFor(PaletteColour::kGreenOne)).b,
            SrgbToLab(SrgbFor(PaletteColour::kGreenZero)).b + 60);
  EXPECT_LE(SrgbToLab(SrgbFor(PaletteColour::kBlack)).l, 15);
}

}  // namespace
}  // namespace pintag
