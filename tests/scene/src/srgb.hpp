#pragma once
// sRGB transfer function as lookup tables, for compositing in linear light at frame speed.

#include <array>
#include <cstdint>

namespace pintag::scene::detail {

/// 8-bit sRGB code value → linear light in [0, 1].
const std::array<float, 256>& SrgbToLinearTable();

/// Linear light → 8-bit sRGB code value (clamped), through a 65,536-entry table.
std::uint8_t LinearToSrgb8(float linear);

}  // namespace pintag::scene::detail
