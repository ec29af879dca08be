#pragma once
// Integer stand-ins for CIELAB a*, b* and L* of an sRGB pixel (D65), used instead of a float
// conversion: three 256-entry tables take the codes to 16-bit linear light, integer dot products
// give X/Xn, Y and Z/Zn, and one 8192-entry table replaces the cube root. Results are in 1/16 of a
// CIELAB unit and stay within about one unit of the exact conversion (tests/detector/lab_approx).

#include <array>
#include <cstdint>

namespace pintag::stage {

inline constexpr int kLabScale = 16;  ///< stand-in values are CIELAB units × 16

class LabApprox {
 public:
  static const LabApprox& Get();

  /// X/Xn, Y, Z/Zn in 0 … 65535 for sRGB codes.
  void xyz(int r, int g, int b, int* x, int* y, int* z) const {
    const std::int32_t lr = linear_[r], lg = linear_[g], lb = linear_[b];
    *x = Clamp((kM[0][0] * lr + kM[0][1] * lg + kM[0][2] * lb + kRound) >> kShift);
    *y = Clamp((kM[1][0] * lr + kM[1][1] * lg + kM[1][2] * lb + kRound) >> kShift);
    *z = Clamp((kM[2][0] * lr + kM[2][1] * lg + kM[2][2] * lb + kRound) >> kShift);
  }
  /// a* × 16.
  int aStar(int r, int g, int b) const {
    int x, y, z;
    xyz(r, g, b, &x, &y, &z);
    return (500 * (cubeRoot(x) - cubeRoot(y))) >> (kFShift - 4);
  }
  /// b* × 16.
  int bStar(int r, int g, int b) const {
    int x, y, z;
    xyz(r, g, b, &x, &y, &z);
    return (200 * (cubeRoot(y) - cubeRoot(z))) >> (kFShift - 4);
  }
  /// L* × 16.
  int lStar(int r, int g, int b) const {
    const int y = Clamp(
        (kM[1][0] * linear_[r] + kM[1][1] * linear_[g] + kM[1][2] * linear_[b] + kRound) >> kShift);
    return ((116 * cubeRoot(y)) >> (kFShift - 4)) - 16 * 16;
  }
  /// a*, b* (× 16) in one go.
  void abStar(int r, int g, int b, int* a_out, int* b_out) const {
    int x, y, z;
    xyz(r, g, b, &x, &y, &z);
    const int fy = cubeRoot(y);
    *a_out = (500 * (cubeRoot(x) - fy)) >> (kFShift - 4);
    *b_out = (200 * (fy - cubeRoot(z))) >> (kFShift - 4);
  }

 private:
  LabApprox();
  static constexpr int kShift = 14;
  static constexpr std::int32_t kRound = 1 << (kShift - 1);
  static constexpr int kFShift = 16;  ///< f values are scaled by 2^16
  static constexpr int kFBits = 13;   ///< table entries
  // sRGB -> XYZ (D65), rows pre-divided by the white point, × 2^14.
  static constexpr std::int32_t kM[3][3] = {
      {7110, 6164, 3110}, {3484, 11717, 1183}, {291, 1793, 14300}};
  static int Clamp(std::int32_t v) { return v < 0 ? 0 : (v > 65535 ? 65535 : v); }
  int cubeRoot(int t) const {
    // Linear interpolation between table entries keeps the cube root's steep start accurate.
    const int i = t >> (16 - kFBits);
    const int frac = t & ((1 << (16 - kFBits)) - 1);
    return f_[i] + (((f_[i + 1] - f_[i]) * frac) >> (16 - kFBits));
  }
  std::array<std::uint16_t, 256> linear_{};
  std::array<std::int32_t, (1 << kFBits) + 1> f_{};
};

}  // namespace pintag::stage
