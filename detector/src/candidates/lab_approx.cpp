#include "candidates/lab_approx.hpp"

#include <cmath>

namespace pintag::stage {

LabApprox::LabApprox() {
  for (int c = 0; c < 256; ++c) {
    const double v = c / 255.0;
    const double lin = v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
    linear_[c] = static_cast<std::uint16_t>(std::lround(lin * 65535.0));
  }
  for (int i = 0; i <= (1 << kFBits); ++i) {
    const double t = static_cast<double>(i) / (1 << kFBits);
    const double f = t > 216.0 / 24389.0 ? std::cbrt(t) : (24389.0 / 27.0 * t + 16.0) / 116.0;
    f_[i] = static_cast<std::int32_t>(std::lround(f * (1 << kFShift)));
  }
}

const LabApprox& LabApprox::Get() {
  static const LabApprox instance;
  return instance;
}

}  // namespace pintag::stage
