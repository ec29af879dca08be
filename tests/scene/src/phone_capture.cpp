#include "phone_capture.hpp"

#include <turbojpeg.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <numbers>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <vector>

#include "bayer.hpp"
#include "srgb.hpp"

namespace pintag::scene {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;

/// A white balance set for another light: each channel's gain, plus a little of the neighbouring
/// channels (a sensor's colour filters overlap).
cv::Matx33d RandomCast(Rng& rng, double strength) {
  // Warm (tungsten) or cool (shade), or greenish (fluorescent), by `strength` (0 … 1).
  cv::Vec3d gain(1, 1, 1);  // B, G, R
  switch (rng.below(3)) {
    case 0:
      gain = {1 - 0.45 * strength, 1 - 0.15 * strength, 1};
      break;
    case 1:
      gain = {1, 1 - 0.1 * strength, 1 - 0.3 * strength};
      break;
    default:
      gain = {1 - 0.15 * strength, 1, 1 - 0.2 * strength};
      break;
  }
  cv::Matx33d m = cv::Matx33d::eye();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      m(r, c) = (r == c ? 1.0 : rng.uniform(0, 0.04 * strength)) * gain[r];
    }
  }
  return m;
}

/// The noise of a sensor whose code value at mid-grey moves by about `code_values` (8-bit sRGB).
void SetNoise(PhoneCapture& p, double code_values, Rng& rng) {
  // At linear 0.2 (sRGB ~124) one 8-bit code value is ~0.0035 of linear light.
  const double sigma_mid = 0.0035 * code_values;
  const double read_share = rng.uniform(0.15, 0.4);  // of the variance at mid-grey
  p.read_noise = sigma_mid * std::sqrt(read_share);
  p.shot_noise = sigma_mid * sigma_mid * (1 - read_share) / 0.2;
}

/// Linear light → sRGB in [0, 1] (exact curve, not the 8-bit table: the ISP works in more bits).
float ToSrgb(float l) {
  l = std::clamp(l, 0.0f, 1.0f);
  return l <= 0.0031308f ? 12.92f * l : 1.055f * std::pow(l, 1.0f / 2.4f) - 0.055f;
}

void ApplyLight(cv::Mat& linear, const PhoneCapture& p) {
  cv::transform(linear, linear, p.cast);
  const double dx = std::cos(p.gradient_angle_deg * kDegToRad);
  const double dy = std::sin(p.gradient_angle_deg * kDegToRad);
  const double w = linear.cols - 1, h = linear.rows - 1;
  const double corners[4] = {0, dx * w, dy * h, dx * w + dy * h};
  const double lowest = *std::min_element(corners, corners + 4);
  const double span = std::max(1e-9, *std::max_element(corners, corners + 4) - lowest);
  for (int y = 0; y < linear.rows; ++y) {
    auto* row = linear.ptr<float>(y);
    for (int x = 0; x < linear.cols; ++x) {
      const double t = (dx * x + dy * y - lowest) / span;
      const auto gain = static_cast<float>(p.exposure * (1 - p.gradient * t));
      const std::size_t i = 3 * static_cast<std::size_t>(x);
      row[i] *= gain;
      row[i + 1] *= gain;
      row[i + 2] *= gain;
    }
  }
}

/// A line of `length` px at `angle` as a kernel: drawn anti-aliased at 8× and area-reduced.
cv::Mat MotionKernel(double length, double angle_deg) {
  constexpr int kFine = 8;
  const int side = 2 * static_cast<int>(std::ceil(length / 2)) + 3;
  cv::Mat fine = cv::Mat::zeros(side * kFine, side * kFine, CV_32F);
  const double c = side * kFine / 2.0, half = length * kFine / 2;
  const double dx = std::cos(angle_deg * kDegToRad) * half;
  const double dy = std::sin(angle_deg * kDegToRad) * half;
  constexpr int kShift = 4;
  const auto at = [&](double v) { return static_cast<int>(std::lround(v * (1 << kShift))); };
  cv::line(fine, cv::Point(at(c - dx), at(c - dy)), cv::Point(at(c + dx), at(c + dy)),
           cv::Scalar(1), kFine / 2, cv::LINE_AA, kShift);
  cv::Mat kernel;
  cv::resize(fine, kernel, cv::Size(side, side), 0, 0, cv::INTER_AREA);
  kernel /= cv::sum(kernel)[0];
  return kernel;
}

/// 65,536 standard normal draws from a fixed seed. Sensing draws about two million values a frame;
/// picking them from this table by 16 random bits costs a tenth of Box–Muller's sin, cos and log,
/// and noise this fine does not need the tails beyond ~4 sigma that the table lacks.
const std::vector<float>& NormalTable() {
  static const std::vector<float> table = [] {
    Rng rng(0x4E6F726D616CULL);
    std::vector<float> t(1U << 16);
    for (float& v : t) v = static_cast<float>(rng.normal());
    return t;
  }();
  return table;
}

/// One colour per pixel in the phase's Bayer pattern, with shot and read noise, as 12-bit values;
/// then OpenCV's edge-aware demosaic (12-bit BGR codes, 0 … 4095). Without `mosaic`, every pixel
/// keeps its three colours, with the same noise.
cv::Mat Sense(const cv::Mat& linear, const PhoneCapture& p, Rng& rng) {
  const std::vector<float>& normal = NormalTable();
  const auto read_variance = static_cast<float>(p.read_noise * p.read_noise);
  const auto shot = static_cast<float>(p.shot_noise);
  // One sensed value: linear light `v` with its noise, a standard normal picked by 16 random bits.
  const auto sensed = [&](float v, std::uint64_t draw) {
    const float sigma = std::sqrt(read_variance + shot * std::max(0.0f, v));
    const float noisy = v + sigma * normal[draw & 0xFFFFU];
    return static_cast<std::uint16_t>(std::clamp(noisy * 4095.0f + 0.5f, 0.0f, 4095.0f));
  };
  if (!p.mosaic) {
    cv::Mat codes(linear.size(), CV_16UC3);
    for (int y = 0; y < linear.rows; ++y) {
      const auto* src = linear.ptr<float>(y);
      auto* dst = codes.ptr<std::uint16_t>(y);
      for (int i = 0; i < 3 * linear.cols; ++i) dst[i] = sensed(src[i], rng.next());
    }
    return codes;
  }
  cv::Mat raw(linear.size(), CV_16UC1);
  for (int y = 0; y < linear.rows; ++y) {
    const auto* src = linear.ptr<float>(y);
    auto* dst = raw.ptr<std::uint16_t>(y);
    std::uint64_t bits = 0;
    for (int x = 0; x < linear.cols; ++x) {
      if (x % 4 == 0) bits = rng.next();  // four 16-bit draws per 64 bits
      dst[x] =
          sensed(src[3 * x + detail::BayerChannel(x, y, p.bayer_phase)], bits >> (16 * (x % 4)));
    }
  }
  cv::Mat demosaiced;
  cv::demosaicing(raw, demosaiced, detail::BayerDemosaicCode(p.bayer_phase, /*edge_aware=*/true));
  return demosaiced;
}

/// sRGB curve, S-curve, saturation and an unsharp mask on luma (BT.601 YCbCr, as JPEG stores), from
/// Sense's 12-bit codes. The two curves are one table over the 4,096 codes.
cv::Mat Process(const cv::Mat& codes, const PhoneCapture& p) {
  std::array<float, 4096> curve{};
  for (std::size_t i = 0; i < curve.size(); ++i) {
    const float v = ToSrgb(static_cast<float>(i) / 4095.0f);
    curve[i] = v - static_cast<float>(p.contrast * std::sin(2 * std::numbers::pi * v) /
                                      (2 * std::numbers::pi));
  }
  const auto at = [&](std::uint16_t code) { return curve[std::min<std::size_t>(code, 4095)]; };
  cv::Mat luma(codes.size(), CV_32F), cb(codes.size(), CV_32F), cr(codes.size(), CV_32F);
  for (int y = 0; y < codes.rows; ++y) {
    const auto* src = codes.ptr<std::uint16_t>(y);
    auto* l = luma.ptr<float>(y);
    auto* b = cb.ptr<float>(y);
    auto* r = cr.ptr<float>(y);
    for (int x = 0; x < codes.cols; ++x) {
      const std::size_t i = 3 * static_cast<std::size_t>(x);
      const float bv = at(src[i]), gv = at(src[i + 1]), rv = at(src[i + 2]);
      l[x] = 0.299f * rv + 0.587f * gv + 0.114f * bv;
      b[x] = 0.564f * (bv - l[x]) * static_cast<float>(p.saturation);
      r[x] = 0.713f * (rv - l[x]) * static_cast<float>(p.saturation);
    }
  }
  if (p.sharpen_amount > 0) {
    cv::Mat soft;
    cv::GaussianBlur(luma, soft, cv::Size(), p.sharpen_sigma_px, p.sharpen_sigma_px,
                     cv::BORDER_REFLECT);
    luma += static_cast<float>(p.sharpen_amount) * (luma - soft);
  }
  cv::Mat out(codes.size(), CV_8UC3);
  const auto to8 = [](float v) {
    return static_cast<std::uint8_t>(std::clamp(v * 255.0f + 0.5f, 0.0f, 255.0f));
  };
  for (int y = 0; y < codes.rows; ++y) {
    const auto* l = luma.ptr<float>(y);
    const auto* b = cb.ptr<float>(y);
    const auto* r = cr.ptr<float>(y);
    auto* dst = out.ptr<std::uint8_t>(y);
    for (int x = 0; x < codes.cols; ++x) {
      const std::size_t i = 3 * static_cast<std::size_t>(x);
      dst[i] = to8(l[x] + 1.773f * b[x]);
      dst[i + 1] = to8(l[x] - 0.344f * b[x] - 0.714f * r[x]);
      dst[i + 2] = to8(l[x] + 1.403f * r[x]);
    }
  }
  return out;
}

/// 4:2:0 (or 4:4:4) JPEG through TurboJPEG, decoded by OpenCV's libjpeg (fancy upsampling, as
/// viewers do).
cv::Mat JpegRoundTrip(const cv::Mat& bgr, int quality, bool full_chroma) {
  const std::unique_ptr<void, int (*)(tjhandle)> compressor(tjInitCompress(), tjDestroy);
  if (!compressor) throw std::runtime_error("PhoneCapture: tjInitCompress failed");
  unsigned char* jpeg = nullptr;
  unsigned long size = 0;  // NOLINT(google-runtime-int): TurboJPEG's type
  const int status = tjCompress2(
      compressor.get(), bgr.data, bgr.cols, static_cast<int>(bgr.step), bgr.rows, TJPF_BGR, &jpeg,
      &size, full_chroma ? TJSAMP_444 : TJSAMP_420, std::clamp(quality, 1, 100), 0);
  const std::unique_ptr<unsigned char, void (*)(unsigned char*)> owned(jpeg, tjFree);
  if (status != 0) {
    throw std::runtime_error(std::string("PhoneCapture: JPEG at quality ") +
                             std::to_string(quality) + ": " + tjGetErrorStr2(compressor.get()));
  }
  const cv::Mat bytes(1, static_cast<int>(size), CV_8U, jpeg);
  return cv::imdecode(bytes, cv::IMREAD_COLOR);
}

}  // namespace

PhoneCapture PhoneCapture::Moderate(std::uint64_t seed) {
  Rng rng(seed ^ 0x50686F6E654D6FULL);
  PhoneCapture p;
  p.exposure = rng.uniform(0.8, 1.15);
  p.gradient = rng.uniform(0, 0.25);
  p.gradient_angle_deg = rng.uniform(0, 360);
  p.cast = rng.chance(0.7) ? RandomCast(rng, rng.uniform(0.1, 0.45)) : cv::Matx33d::eye();
  p.defocus_sigma_px = rng.uniform(0.2, 0.8);
  p.motion_px = rng.chance(0.25) ? rng.uniform(0.5, 1.5) : 0;
  p.motion_angle_deg = rng.uniform(0, 180);
  p.bayer_phase = rng.below(4);
  SetNoise(p, rng.uniform(1, 3), rng);
  p.contrast = rng.uniform(0, 0.3);
  p.saturation = rng.uniform(1.0, 1.25);
  p.sharpen_amount = rng.uniform(0.2, 0.8);
  p.sharpen_sigma_px = rng.uniform(0.7, 1.2);
  p.jpeg_quality = 75 + rng.below(21);
  return p;
}

PhoneCapture PhoneCapture::Hard(std::uint64_t seed) {
  Rng rng(seed ^ 0x50686F6E6548ULL);
  PhoneCapture p;
  p.exposure = rng.uniform(0.5, 1.3);
  p.gradient = rng.uniform(0.2, 0.5);
  p.gradient_angle_deg = rng.uniform(0, 360);
  p.cast = RandomCast(rng, rng.uniform(0.5, 1.0));
  p.defocus_sigma_px = rng.uniform(0.6, 1.5);
  p.motion_px = rng.uniform(1, 4);
  p.motion_angle_deg = rng.uniform(0, 180);
  p.bayer_phase = rng.below(4);
  SetNoise(p, rng.uniform(3, 8), rng);
  p.contrast = rng.uniform(0.1, 0.5);
  p.saturation = rng.uniform(0.9, 1.35);
  p.sharpen_amount = rng.uniform(0.5, 1.5);
  p.sharpen_sigma_px = rng.uniform(0.8, 1.5);
  p.jpeg_quality = 45 + rng.below(46);
  return p;
}

namespace detail {

void ApplyPhoneCapture(cv::Mat& frame, const PhoneCapture& capture, Rng& rng) {
  const auto& to_linear = SrgbToLinearTable();
  cv::Mat linear(frame.size(), CV_32FC3);
  for (int y = 0; y < frame.rows; ++y) {
    const auto* src = frame.ptr<std::uint8_t>(y);
    auto* dst = linear.ptr<float>(y);
    for (int i = 0; i < frame.cols * 3; ++i) dst[i] = to_linear[src[i]];
  }
  ApplyLight(linear, capture);
  if (capture.defocus_sigma_px > 0.05) {
    cv::GaussianBlur(linear, linear, cv::Size(), capture.defocus_sigma_px, capture.defocus_sigma_px,
                     cv::BORDER_REFLECT);
  }
  if (capture.motion_px >= 0.25) {
    cv::filter2D(linear, linear, -1, MotionKernel(capture.motion_px, capture.motion_angle_deg),
                 cv::Point(-1, -1), 0, cv::BORDER_REFLECT);
  }
  cv::Mat codes;
  if (capture.sensor_scale > 1) {
    // A finer sensor behind the same optics: the light upsampled, sensed, demosaiced, and the
    // codes area-averaged back to the output's pixels. Averaging k² pixels divides the noise
    // variance by k², so the sensor's own noise is k² times the output's.
    const int k = capture.sensor_scale;
    PhoneCapture fine = capture;
    fine.read_noise *= k;
    fine.shot_noise *= k * k;
    cv::Mat upsampled;
    cv::resize(linear, upsampled, linear.size() * k, 0, 0, cv::INTER_LINEAR);
    cv::resize(Sense(upsampled, fine, rng), codes, linear.size(), 0, 0, cv::INTER_AREA);
  } else {
    codes = Sense(linear, capture, rng);
  }
  frame = Process(codes, capture);
  if (capture.jpeg_quality > 0)
    frame = JpegRoundTrip(frame, capture.jpeg_quality, capture.jpeg_full_chroma);
}

}  // namespace detail
}  // namespace pintag::scene
