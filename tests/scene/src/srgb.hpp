#pragma once
// sRGB transfer function as lookup tables, for compositing in linear light at frame speed.

#include <array>
#include <cstdint>

namespace pintag::scene::detail {

/// 8-bit sRGB code value → linear light in [0, 1].
const std::array<float, 256>& SrgbToLinearTable();

inline constexpr int kLinearSteps = 65535;

/// kLinearSteps + 1 entries: linear light i / kLinearSteps → 8-bit sRGB code value (rounded).
const std::uint8_t* LinearToSrgbTable();

/// Linear light → 8-bit sRGB code value, clamped to [0, 1] first (NaN → 0).
inline std::uint8_t LinearToSrgb8(const std::uint8_t* table, float linear) {
  if (!(linear > 0.0f)) return table[0];
  if (linear >= 1.0f) return table[kLinearSteps];
  // Positive here, so adding a half and truncating rounds; std::lround would cost a libm call
  // for each of a frame's six million values, and a tie either way picks a neighbouring entry.
  // NOLINTNEXTLINE(bugprone-incorrect-roundings)
  return table[static_cast<int>(linear * kLinearSteps + 0.5f)];
}

/// `count` values of linear light → sRGB code values.
void LinearToSrgb8(const float* linear, std::uint8_t* srgb, int count);

}  // namespace pintag::scene::detail
