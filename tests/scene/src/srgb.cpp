#include "srgb.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace pintag::scene::detail {
namespace {

double ToLinear(double v) {
  return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

double ToSrgb(double l) {
  return l <= 0.0031308 ? 12.92 * l : 1.055 * std::pow(l, 1.0 / 2.4) - 0.055;
}

}  // namespace

const std::array<float, 256>& SrgbToLinearTable() {
  static const std::array<float, 256> table = [] {
    std::array<float, 256> t{};
    for (int i = 0; i < 256; ++i) t[i] = static_cast<float>(ToLinear(i / 255.0));
    return t;
  }();
  return table;
}

const std::uint8_t* LinearToSrgbTable() {
  static const std::vector<std::uint8_t> table = [] {
    std::vector<std::uint8_t> t(kLinearSteps + 1);
    for (int i = 0; i <= kLinearSteps; ++i) {
      const double code = std::round(255.0 * ToSrgb(static_cast<double>(i) / kLinearSteps));
      t[i] = static_cast<std::uint8_t>(std::clamp(code, 0.0, 255.0));
    }
    return t;
  }();
  return table.data();
}

void LinearToSrgb8(const float* linear, std::uint8_t* srgb, int count) {
  const std::uint8_t* table = LinearToSrgbTable();
  for (int i = 0; i < count; ++i) {
    // Branch-free clamp (NaN goes to 0 through the max) so the index arithmetic vectorises.
    const float v = std::min(std::max(0.0f, linear[i]), 1.0f);
    // v is clamped to [0, 1], so adding a half and truncating rounds to nearest; it vectorises
    // where lround does not, and every rendered frame depends on these exact indices.
    srgb[i] =
        table[static_cast<int>(v * kLinearSteps + 0.5f)];  // NOLINT(bugprone-incorrect-roundings)
  }
}

}  // namespace pintag::scene::detail
