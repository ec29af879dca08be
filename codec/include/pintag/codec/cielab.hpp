#pragma once
// Exact sRGB (D65) <-> CIELAB conversion, used to define and check the palette. The detector uses
// cheaper stand-ins and is tested against this.

#include <cstdint>

namespace pintag {

struct Rgb8 {
  std::uint8_t r = 0;
  std::uint8_t g = 0;
  std::uint8_t b = 0;
  constexpr bool operator==(const Rgb8&) const = default;
};

struct Lab {
  double l = 0;  ///< lightness, 0 … 100
  double a = 0;  ///< green (−) … red (+)
  double b = 0;  ///< blue (−) … yellow (+)
};

/// sRGB transfer function: 8-bit code value -> linear light in [0, 1].
double SrgbToLinear(std::uint8_t code);
/// Inverse transfer function with rounding and clamping to [0, 255].
std::uint8_t LinearToSrgb(double linear);

Lab SrgbToLab(Rgb8 colour);
/// Nearest 8-bit sRGB colour (out-of-gamut components are clamped).
Rgb8 LabToSrgb(Lab colour);

/// CIE76 colour difference: Euclidean distance in CIELAB.
double DeltaE76(Lab first, Lab second);

}  // namespace pintag
