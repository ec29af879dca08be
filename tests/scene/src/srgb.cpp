#include "srgb.hpp"

#include <cmath>
#include <vector>

namespace pintag::scene::detail {
namespace {

constexpr int kLinearSteps = 65535;

double ToLinear(double v) {
  return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

double ToSrgb(double l) {
  return l <= 0.0031308 ? 12.92 * l : 1.055 * std::pow(l, 1.0 / 2.4) - 0.055;
}

const std::vector<std::uint8_t>& LinearTable() {
  static const std::vector<std::uint8_t> table = [] {
    std::vector<std::uint8_t> t(kLinearSteps + 1);
    for (int i = 0; i <= kLinearSteps; ++i) {
      const double code = std::round(255.0 * ToSrgb(static_cast<double>(i) / kLinearSteps));
      t[i] = static_cast<std::uint8_t>(code < 0 ? 0 : code > 255 ? 255 : code);
    }
    return t;
  }();
  return table;
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

const std::uint8_t* Linear16ToSrgbTable() {
  return LinearTable().data();
}

std::uint8_t LinearToSrgb8(float linear) {
  static const std::vector<std::uint8_t>& table = LinearTable();
  if (!(linear > 0.0f)) return table[0];  // also NaN
  if (linear >= 1.0f) return 255;
  return table[static_cast<int>(linear * kLinearSteps + 0.5f)];
}

}  // namespace pintag::scene::detail
