#include "pintag/codec/cielab.hpp"

#include <algorithm>
#include <cmath>

namespace pintag {
namespace {

// D65 reference white, CIE 1931 2° observer.
constexpr double kWhiteX = 0.95047;
constexpr double kWhiteY = 1.0;
constexpr double kWhiteZ = 1.08883;
constexpr double kDelta = 6.0 / 29.0;

double LabF(double t) {
  return t > kDelta * kDelta * kDelta ? std::cbrt(t) : t / (3 * kDelta * kDelta) + 4.0 / 29.0;
}

double LabFInverse(double t) {
  return t > kDelta ? t * t * t : 3 * kDelta * kDelta * (t - 4.0 / 29.0);
}

}  // namespace

double SrgbToLinear(std::uint8_t code) {
  const double c = code / 255.0;
  return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

std::uint8_t LinearToSrgb(double linear) {
  const double c = std::clamp(linear, 0.0, 1.0);
  const double encoded = c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1 / 2.4) - 0.055;
  return static_cast<std::uint8_t>(std::lround(encoded * 255.0));
}

Lab SrgbToLab(Rgb8 colour) {
  const double r = SrgbToLinear(colour.r);
  const double g = SrgbToLinear(colour.g);
  const double b = SrgbToLinear(colour.b);
  const double x = 0.4124564 * r + 0.3575761 * g + 0.1804375 * b;
  const double y = 0.2126729 * r + 0.7151522 * g + 0.0721750 * b;
  const double z = 0.0193339 * r + 0.1191920 * g + 0.9503041 * b;
  const double fx = LabF(x / kWhiteX);
  const double fy = LabF(y / kWhiteY);
  const double fz = LabF(z / kWhiteZ);
  return {116 * fy - 16, 500 * (fx - fy), 200 * (fy - fz)};
}

Rgb8 LabToSrgb(Lab colour) {
  const double fy = (colour.l + 16) / 116;
  const double fx = fy + colour.a / 500;
  const double fz = fy - colour.b / 200;
  const double x = kWhiteX * LabFInverse(fx);
  const double y = kWhiteY * LabFInverse(fy);
  const double z = kWhiteZ * LabFInverse(fz);
  const double r = 3.2404542 * x - 1.5371385 * y - 0.4985314 * z;
  const double g = -0.9692660 * x + 1.8760108 * y + 0.0415560 * z;
  const double b = 0.0556434 * x - 0.2040259 * y + 1.0572252 * z;
  return {LinearToSrgb(r), LinearToSrgb(g), LinearToSrgb(b)};
}

double DeltaE76(Lab first, Lab second) {
  return std::hypot(first.l - second.l, first.a - second.a, first.b - second.b);
}

}  // namespace pintag
