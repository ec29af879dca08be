#include "photometry.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numbers>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <type_traits>
#include <vector>

#include "bayer.hpp"
#include "srgb.hpp"

namespace pintag::scene {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;

/// Channel gains (B, G, R) in linear light: a white-balance left set for daylight under other
/// light.
cv::Vec3d CastGains(Cast cast) {
  switch (cast) {
    case Cast::kNone:
      return {1, 1, 1};
    case Cast::kTungsten:  // warm: blue well down
      return {0.55, 0.80, 1.0};
    case Cast::kFluorescent:  // green spike
      return {0.85, 1.0, 0.80};
    case Cast::kShade:  // cool: open sky
      return {1.0, 0.90, 0.75};
  }
  return {1, 1, 1};
}

Cast RandomCast(Rng& rng, bool allow_none) {
  const int pick = allow_none ? rng.below(4) : 1 + rng.below(3);
  return static_cast<Cast>(pick);
}

/// Standard normal values for the noise, drawn once from a fixed seed and indexed with 16 random
/// bits per sample (4 samples per 64-bit draw): Box–Muller per pixel would dominate a frame.
const std::vector<float>& NormalTable() {
  static const std::vector<float> table = [] {
    Rng rng(0x5EED5EED);
    std::vector<float> t(1 << 16);
    for (float& v : t) v = static_cast<float>(rng.normal());
    return t;
  }();
  return table;
}

/// Per-pixel gain from exposure, gradient and cast, applied through banded lookup tables: the gain
/// is exposure · cast · (1 − gradient · t), t going 0 → 1 across the frame along the gradient's
/// direction, quantised into 128 bands (steps under 0.5 %). `Out` is std::uint8_t (sRGB out) or
/// float (linear light out, for blurring).
template <typename Out>
cv::Mat ApplyLight(const cv::Mat& frame, const Photometry& p) {
  const cv::Vec3d cast = CastGains(p.cast);
  const bool flat = p.gradient <= 0;
  constexpr bool kLinearOut = std::is_same_v<Out, float>;
  const int bands = flat ? 1 : 128;
  const auto& to_linear = detail::SrgbToLinearTable();
  std::vector<std::array<Out, std::size_t{256} * 3>> luts(bands);
  for (int b = 0; b < bands; ++b) {
    const double t = flat ? 0.0 : (b + 0.5) / bands;
    const double gain = p.exposure * (1.0 - std::clamp(p.gradient, 0.0, 1.0) * t);
    for (int c = 0; c < 3; ++c) {
      for (int v = 0; v < 256; ++v) {
        const double linear = gain * cast[c] * to_linear[v];
        if constexpr (kLinearOut) {
          luts[b][c * 256 + v] = static_cast<float>(linear);  // saturates after the blur
        } else {
          luts[b][c * 256 + v] =
              detail::LinearToSrgb8(detail::LinearToSrgbTable(), static_cast<float>(linear));
        }
      }
    }
  }
  const double dx = std::cos(p.gradient_angle_deg * kDegToRad);
  const double dy = std::sin(p.gradient_angle_deg * kDegToRad);
  // t(x, y) = (dx·x + dy·y − lowest) / span over the frame's corners.
  const double w = frame.cols - 1, h = frame.rows - 1;
  const double corners[4] = {0, dx * w, dy * h, dx * w + dy * h};
  const double lowest = *std::min_element(corners, corners + 4);
  const double span = std::max(1e-9, *std::max_element(corners, corners + 4) - lowest);
  cv::Mat out(frame.size(), CV_MAKETYPE(cv::DataType<Out>::depth, 3));
  const double band_step_x = flat ? 0.0 : dx * bands / span;
  for (int y = 0; y < frame.rows; ++y) {
    const auto* src = frame.ptr<std::uint8_t>(y);
    auto* dst = out.ptr<Out>(y);
    double band_at = flat ? 0.0 : (dy * y - lowest) * bands / span;  // band position at x = 0
    for (int x = 0; x < frame.cols; ++x, band_at += band_step_x) {
      const int band = std::clamp(static_cast<int>(band_at), 0, bands - 1);
      const Out* lut = luts[band].data();
      const std::ptrdiff_t i = 3 * static_cast<std::ptrdiff_t>(x);
      dst[i] = lut[src[i]];
      dst[i + 1] = lut[256 + src[i + 1]];
      dst[i + 2] = lut[512 + src[i + 2]];
    }
  }
  return out;
}

void ApplyMotionBlur(cv::Mat& frame, double length_px, double angle_deg) {
  const double dx = std::cos(angle_deg * kDegToRad), dy = std::sin(angle_deg * kDegToRad);
  // The kernel's box fits the segment (plus a pixel for the bilinear splat): a nearly horizontal
  // blur gets a wide, short kernel, which filter2D runs much faster than a square one.
  const int half_x = static_cast<int>(std::ceil(std::abs(dx) * length_px / 2)) + 1;
  const int half_y = static_cast<int>(std::ceil(std::abs(dy) * length_px / 2)) + 1;
  cv::Mat kernel = cv::Mat::zeros(2 * half_y + 1, 2 * half_x + 1, CV_32F);
  // Splat many points along a centred segment bilinearly: a smooth, sub-pixel line kernel.
  const int steps = 32 * (static_cast<int>(length_px) + 1);
  for (int i = 0; i <= steps; ++i) {
    const double s = (static_cast<double>(i) / steps - 0.5) * length_px;
    const double x = half_x + s * dx, y = half_y + s * dy;
    const int ix = static_cast<int>(std::floor(x)), iy = static_cast<int>(std::floor(y));
    const double ax = x - ix, ay = y - iy;
    kernel.at<float>(iy, ix) += static_cast<float>((1 - ax) * (1 - ay));
    kernel.at<float>(iy, ix + 1) += static_cast<float>(ax * (1 - ay));
    kernel.at<float>(iy + 1, ix) += static_cast<float>((1 - ax) * ay);
    kernel.at<float>(iy + 1, ix + 1) += static_cast<float>(ax * ay);
  }
  kernel /= cv::sum(kernel)[0];
  cv::filter2D(frame, frame, -1, kernel, cv::Point(-1, -1), 0, cv::BORDER_REFLECT);
}

/// Replaces each 8-bit sample v of `frame` by noisy(v, d), d a 16-bit draw that indexes
/// NormalTable (four draws from each 64 random bits).
template <typename Noisy>
void AddNoise(cv::Mat& frame, Rng& rng, Noisy noisy) {
  for (int y = 0; y < frame.rows; ++y) {
    auto* row = frame.ptr<std::uint8_t>(y);
    const int n = frame.cols * frame.channels();
    std::uint64_t bits = 0;
    for (int i = 0; i < n; ++i) {
      if ((i & 3) == 0) bits = rng.next();
      row[i] = noisy(row[i], static_cast<std::uint16_t>(bits & 0xFFFF));
      bits >>= 16;
    }
  }
}

/// Noise whose spread depends on the code value it lands on: read noise plus shot noise in linear
/// light, through the sRGB curve's slope, `sigma` code values at mid-grey (linear 0.2).
void ApplySensorNoise(cv::Mat& frame, double sigma, double read_share, Rng& rng) {
  const auto srgb_slope = [](double linear) {  // d sRGB / d linear
    return linear <= 0.0031308 ? 12.92 : 1.055 / 2.4 * std::pow(linear, 1 / 2.4 - 1);
  };
  constexpr double kMidGrey = 0.2;
  const auto& to_linear = detail::SrgbToLinearTable();
  std::array<float, 256> spread{};
  for (std::size_t v = 0; v < spread.size(); ++v) {
    const double linear = to_linear[v];
    const double relative_sd = std::sqrt(read_share + (1 - read_share) * linear / kMidGrey);
    spread[v] = static_cast<float>(sigma * relative_sd * srgb_slope(linear) / srgb_slope(kMidGrey));
  }
  const auto& normal = NormalTable();
  AddNoise(frame, rng, [&](std::uint8_t v, std::uint16_t draw) {
    const float noisy = static_cast<float>(v) + spread[v] * normal[draw] + 0.5f;
    return static_cast<std::uint8_t>(std::clamp(noisy, 0.0f, 255.0f));
  });
}

void ApplyNoise(cv::Mat& frame, double sigma, Rng& rng) {
  // Rounding the noise before adding it to an integer is the same as rounding the sum.
  const auto& normal = NormalTable();
  std::vector<std::int16_t> table(normal.size());
  for (std::size_t i = 0; i < table.size(); ++i) {
    table[i] = static_cast<std::int16_t>(std::clamp(std::lround(sigma * normal[i]), -255L, 255L));
  }
  AddNoise(frame, rng, [&](std::uint8_t v, std::uint16_t draw) {
    const int noisy = v + table[draw];
    return static_cast<std::uint8_t>(noisy < 0 ? 0 : noisy > 255 ? 255 : noisy);
  });
}

/// One colour per pixel of `bgr` (8-bit) in the phase's Bayer pattern (bayer.hpp).
cv::Mat Mosaic(const cv::Mat& bgr, int phase) {
  cv::Mat mosaic(bgr.size(), CV_8UC1);
  for (int y = 0; y < bgr.rows; ++y) {
    const auto* src = bgr.ptr<std::uint8_t>(y);
    auto* dst = mosaic.ptr<std::uint8_t>(y);
    for (int x = 0; x < bgr.cols; ++x) dst[x] = src[3 * x + detail::BayerChannel(x, y, phase)];
  }
  return mosaic;
}

/// Rows by which OpenCV's VNG demosaic moves the picture up (2 in OpenCV 4.6: opencv/opencv issue
/// 5089), measured once on a smooth test picture so that an OpenCV without the fault needs none.
int VngRowsUp() {
  static const int rows = [] {
    cv::Mat picture(64, 64, CV_8UC3);
    for (int y = 0; y < picture.rows; ++y) {
      for (int x = 0; x < picture.cols; ++x) {
        const double a = 0.3 * x + 0.2 * y, b = 0.25 * y - 0.15 * x;
        picture.at<cv::Vec3b>(y, x) =
            cv::Vec3b(cv::saturate_cast<std::uint8_t>(128 + 90 * std::sin(a)),
                      cv::saturate_cast<std::uint8_t>(128 + 90 * std::sin(b)),
                      cv::saturate_cast<std::uint8_t>(128 + 90 * std::cos(a + b)));
      }
    }
    cv::Mat demosaiced;
    cv::demosaicing(Mosaic(picture, 0), demosaiced, detail::BayerVngDemosaicCode(0));
    const cv::Rect inside(8, 8, 48, 48);
    int best = 0;
    double least = std::numeric_limits<double>::infinity();
    for (int up = -4; up <= 4; ++up) {
      const double error =
          cv::norm(picture(inside), demosaiced(inside - cv::Point(0, up)), cv::NORM_L1);
      if (error < least) least = error, best = up;
    }
    return best;
  }();
  return rows;
}

/// Keeps one colour per pixel in the phase's Bayer pattern, then demosaics bilinearly or (`vng`)
/// by variable numbers of gradients, put back where the scene is.
void ApplyBayer(cv::Mat& frame, int phase, bool vng) {
  const cv::Mat mosaic = Mosaic(frame, phase);
  if (!vng) {
    cv::demosaicing(mosaic, frame, detail::BayerDemosaicCode(phase, /*edge_aware=*/false));
    return;
  }
  cv::Mat demosaiced;
  cv::demosaicing(mosaic, demosaiced, detail::BayerVngDemosaicCode(phase));
  const int up = VngRowsUp();
  const cv::Matx23d shift(1, 0, 0, 0, 1, up);
  cv::warpAffine(demosaiced, frame, shift, frame.size(), cv::INTER_NEAREST, cv::BORDER_REPLICATE);
}

/// A phone's processing in 8-bit sRGB: tone power and S-curve, saturation and colour denoising on
/// the differences from the channels' mean, then an unsharp mask on each channel.
void ApplyProcessing(cv::Mat& frame, const Photometry& p) {
  const bool tone = std::abs(p.tone_gamma - 1) > 1e-3;
  const bool s_curve = p.tone_contrast > 1e-3;
  const bool colour = std::abs(p.saturation - 1) > 1e-3 || p.chroma_denoise_px > 0.05;
  if (!tone && !s_curve && !colour && p.sharpen <= 0) return;
  cv::Mat f;
  frame.convertTo(f, CV_32FC3, 1.0 / 255);
  if (tone) cv::pow(cv::max(f, 0.0), p.tone_gamma, f);
  if (s_curve) {
    const auto c = static_cast<float>(std::min(p.tone_contrast, 1.0));
    f.forEach<cv::Vec3f>([c](cv::Vec3f& pixel, const int* /*position*/) {
      for (int i = 0; i < 3; ++i) {
        const float v = std::clamp(pixel[i], 0.0f, 1.0f);
        pixel[i] = v + c * (v * v * (3 - 2 * v) - v);  // towards the smoothstep
      }
    });
  }
  if (colour) {
    std::vector<cv::Mat> channels;
    cv::split(f, channels);
    const cv::Mat mean = (channels[0] + channels[1] + channels[2]) / 3;
    for (cv::Mat& c : channels) {
      cv::Mat difference = c - mean;
      if (p.chroma_denoise_px > 0.05) {
        cv::GaussianBlur(difference, difference, cv::Size(), p.chroma_denoise_px,
                         p.chroma_denoise_px, cv::BORDER_REFLECT);
      }
      c = mean + p.saturation * difference;
    }
    cv::merge(channels, f);
  }
  if (p.sharpen > 0) {
    cv::Mat soft;
    cv::GaussianBlur(f, soft, cv::Size(), p.sharpen_sigma_px, p.sharpen_sigma_px,
                     cv::BORDER_REFLECT);
    f += p.sharpen * (f - soft);
  }
  f.convertTo(frame, CV_8UC3, 255);  // rounds and saturates
}

}  // namespace

Photometry Photometry::Moderate(std::uint64_t seed) {
  Rng rng(seed ^ 0x4D6F646572617465ULL);
  Photometry p;
  p.gradient = rng.uniform(0, 0.3);
  p.gradient_angle_deg = rng.uniform(0, 360);
  p.cast = RandomCast(rng, true);
  p.defocus_sigma_px = rng.uniform(0, 1.0);
  p.motion_px = rng.chance(0.5) ? rng.uniform(0, 2.0) : 0;
  p.motion_angle_deg = rng.uniform(0, 180);
  p.noise_sigma = rng.uniform(1, 4);
  p.jpeg_quality = 75 + rng.below(21);
  p.exposure = rng.uniform(0.8, 1.15);
  p.tone_gamma = rng.uniform(0.85, 1.15);
  p.saturation = rng.uniform(0.95, 1.3);
  p.chroma_denoise_px = rng.chance(0.5) ? rng.uniform(0.5, 1.5) : 0;
  p.sharpen = rng.uniform(0, 1.0);
  p.sharpen_sigma_px = rng.uniform(0.6, 1.2);
  // Drawn last, so that every setting above is what it was before moderate light had a colour
  // filter array (a phone always has one; the held-out phone demosaics edge-aware, this one
  // bilinearly).
  p.bayer = rng.chance(0.75);
  p.bayer_phase = rng.below(4);
  // Drawn after everything above, for the same reason.
  p.read_noise_share = rng.chance(0.5) ? rng.uniform(0.1, 0.5) : 1.0;
  return p;
}

Photometry Photometry::Hard(std::uint64_t seed) {
  Rng rng(seed ^ 0x48617264ULL);
  Photometry p;
  p.gradient = rng.uniform(0.3, 0.6);
  p.gradient_angle_deg = rng.uniform(0, 360);
  p.cast = RandomCast(rng, false);
  p.defocus_sigma_px = rng.uniform(0.8, 2.0);
  p.motion_px = rng.uniform(1.5, 5.0);
  p.motion_angle_deg = rng.uniform(0, 180);
  p.noise_sigma = rng.uniform(4, 9);
  p.jpeg_quality = 40 + rng.below(56);
  p.exposure = rng.uniform(0.55, 1.3);
  p.bayer = rng.chance(0.5);
  p.tone_gamma = rng.uniform(0.75, 1.25);
  p.saturation = rng.uniform(0.85, 1.4);
  p.chroma_denoise_px = rng.uniform(0.5, 2.0);
  p.sharpen = rng.uniform(0.3, 1.6);
  p.sharpen_sigma_px = rng.uniform(0.7, 1.5);
  // Drawn last: a phone that keeps its colour noise (as the held-out world's does), and a sensor's
  // noise, which gives the tag's black more colour noise than its elements.
  if (rng.chance(0.3)) p.chroma_denoise_px = 0;
  p.read_noise_share = rng.chance(0.5) ? rng.uniform(0.1, 0.5) : 1.0;
  return p;
}

namespace detail {

void ApplyPhotometry(cv::Mat& frame, const Photometry& p, Rng& rng) {
  const bool defocus = p.defocus_sigma_px > 0.05, motion = p.motion_px >= 0.25;
  if (defocus || motion) {
    // Light and optics act on linear light, before the camera's tone curve.
    cv::Mat linear = ApplyLight<float>(frame, p);
    if (defocus) {
      cv::GaussianBlur(linear, linear, cv::Size(), p.defocus_sigma_px, p.defocus_sigma_px,
                       cv::BORDER_REFLECT);
    }
    if (motion) ApplyMotionBlur(linear, p.motion_px, p.motion_angle_deg);
    for (int y = 0; y < frame.rows; ++y) {
      LinearToSrgb8(linear.ptr<float>(y), frame.ptr<std::uint8_t>(y), frame.cols * 3);
    }
  } else if (p.gradient > 0 || p.exposure != 1.0 || p.cast != Cast::kNone) {
    frame = ApplyLight<std::uint8_t>(frame, p);
  }
  if (p.noise_sigma > 0) {
    if (p.read_noise_share < 1) {
      ApplySensorNoise(frame, p.noise_sigma, p.read_noise_share, rng);
    } else {
      ApplyNoise(frame, p.noise_sigma, rng);
    }
  }
  if (p.bayer) ApplyBayer(frame, p.bayer_phase, p.vng_demosaic);
  ApplyProcessing(frame, p);
  if (p.jpeg_quality > 0) {
    std::vector<std::uint8_t> bytes;
    cv::imencode(".jpg", frame, bytes,
                 {cv::IMWRITE_JPEG_QUALITY, std::clamp(p.jpeg_quality, 1, 100)});
    frame = cv::imdecode(bytes, cv::IMREAD_COLOR);
  }
}

}  // namespace detail
}  // namespace pintag::scene
