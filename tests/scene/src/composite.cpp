#include "composite.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "srgb.hpp"

namespace pintag::scene::detail {
namespace {

cv::Point2d Map(const cv::Matx33d& h, double x, double y, double* w = nullptr) {
  const double d = h(2, 0) * x + h(2, 1) * y + h(2, 2);
  if (w != nullptr) *w = d;
  return {(h(0, 0) * x + h(0, 1) * y + h(0, 2)) / d, (h(1, 0) * x + h(1, 1) * y + h(1, 2)) / d};
}

/// Smallest singular value of the Jacobian of `h` at (x, y): texels per frame pixel in the
/// direction where the texture is least compressed.
double MinStretch(const cv::Matx33d& h, double x, double y) {
  const cv::Point2d p = Map(h, x, y), px = Map(h, x + 1, y), py = Map(h, x, y + 1);
  const double a = px.x - p.x, b = py.x - p.x, c = px.y - p.y, d = py.y - p.y;
  const double s1 = a * a + b * b + c * c + d * d, det = a * d - b * c;
  const double disc = std::sqrt(std::max(0.0, s1 * s1 - 4 * det * det));
  return std::sqrt(std::max(0.0, (s1 - disc) / 2));
}

}  // namespace

LinearTexture PrepareTexture(const MarkerTexture& texture, const std::vector<Occluder>& occluders) {
  cv::Mat bgr = texture.bgr;
  if (!occluders.empty()) {
    bgr = texture.bgr.clone();
    const auto& c = texture.square_corners_px;
    constexpr int kShift = 4;  // sub-pixel drawing precision, 1/16 px
    constexpr double kScale = 1 << kShift;
    for (const Occluder& o : occluders) {
      const cv::Point2d centre = c[0] + o.centre.x * (c[1] - c[0]) + o.centre.y * (c[3] - c[0]);
      const double radius = o.radius * cv::norm(c[1] - c[0]);
      cv::circle(bgr, cv::Point(cvRound(centre.x * kScale), cvRound(centre.y * kScale)),
                 cvRound(radius * kScale), o.bgr, cv::FILLED, cv::LINE_AA, kShift);
    }
  }
  // Linear light with coverage 1 in the fourth channel: warped with a zero border, the fourth
  // channel becomes the anti-aliased coverage of the texture's outline.
  const auto& to_linear = SrgbToLinearTable();
  LinearTexture result;
  result.base.create(bgr.size(), CV_32FC4);
  for (int y = 0; y < bgr.rows; ++y) {
    const auto* src = bgr.ptr<std::uint8_t>(y);
    auto* dst = result.base.ptr<float>(y);
    for (int x = 0; x < bgr.cols; ++x, src += 3, dst += 4) {
      dst[0] = to_linear[src[0]];
      dst[1] = to_linear[src[1]];
      dst[2] = to_linear[src[2]];
      dst[3] = 1.0f;
    }
  }
  return result;
}

bool CompositeMarker(cv::Mat& frame, const LinearTexture& texture,
                     const cv::Matx33d& image_from_texture, int supersample) {
  const cv::Mat& base = texture.base;
  const double tw = base.cols, th = base.rows;
  // The texture's outer edge in the frame; all of it must be in front of the camera.
  const cv::Point2d edge[4] = {
      {-0.5, -0.5}, {tw - 0.5, -0.5}, {tw - 0.5, th - 0.5}, {-0.5, th - 0.5}};
  double x_min = 1e300, x_max = -1e300, y_min = 1e300, y_max = -1e300;
  for (const cv::Point2d& e : edge) {
    double w = 0;
    const cv::Point2d p = Map(image_from_texture, e.x, e.y, &w);
    if (!(w > 1e-9)) return false;
    x_min = std::min(x_min, p.x), x_max = std::max(x_max, p.x);
    y_min = std::min(y_min, p.y), y_max = std::max(y_max, p.y);
  }
  const int x0 = std::max(0, static_cast<int>(std::floor(x_min)));
  const int y0 = std::max(0, static_cast<int>(std::floor(y_min)));
  const int x1 = std::min(frame.cols - 1, static_cast<int>(std::ceil(x_max)));
  const int y1 = std::min(frame.rows - 1, static_cast<int>(std::ceil(y_max)));
  if (x0 > x1 || y0 > y1) return true;  // wholly outside the frame

  const cv::Matx33d texture_from_image = image_from_texture.inv();
  const int ss = std::clamp(supersample, 1, 8);
  // Mip level: a texel at that level no larger than a sub-sample, measured where the texture is
  // least compressed (so nothing gets blurrier than the sub-sample grid).
  const cv::Point2d middle = Map(image_from_texture, (tw - 1) / 2, (th - 1) / 2);
  const double stretch = MinStretch(texture_from_image, middle.x, middle.y) / ss;
  int level = 0;
  while (stretch >= (2 << level) && (base.cols >> (level + 1)) >= 8) ++level;
  cv::Mat tex = base;
  if (level > 0) {
    cv::resize(base, tex, cv::Size(), 1.0 / (1 << level), 1.0 / (1 << level), cv::INTER_AREA);
  }
  // Texture coordinates at `level`: u_l = (u + 0.5) · sx − 0.5 (the sizes may round).
  const double sx = static_cast<double>(tex.cols) / base.cols;
  const double sy = static_cast<double>(tex.rows) / base.rows;
  const cv::Matx33d to_level(sx, 0, 0.5 * sx - 0.5, 0, sy, 0.5 * sy - 0.5, 0, 0, 1);
  // Sub-sample canvas pixel (X, Y) has its centre at frame point x0 − 0.5 + (X + 0.5) / ss.
  const double inv = 1.0 / ss;
  const cv::Matx33d frame_from_canvas(inv, 0, x0 - 0.5 + 0.5 * inv, 0, inv, y0 - 0.5 + 0.5 * inv, 0,
                                      0, 1);
  const cv::Matx33d level_from_canvas = to_level * texture_from_image * frame_from_canvas;
  const cv::Size box(x1 - x0 + 1, y1 - y0 + 1);
  cv::Mat canvas;
  cv::warpPerspective(
      tex, canvas, cv::Mat(level_from_canvas), cv::Size(box.width * ss, box.height * ss),
      cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_CONSTANT, cv::Scalar::all(0));
  cv::Mat area = canvas;
  if (ss > 1) cv::resize(canvas, area, box, 0, 0, cv::INTER_AREA);

  const auto& to_linear = SrgbToLinearTable();
  const std::uint8_t* to_srgb = LinearToSrgbTable();
  for (int y = 0; y < box.height; ++y) {
    const float* src = area.ptr<float>(y);
    std::uint8_t* out = frame.ptr<std::uint8_t>(y + y0, x0);
    for (int x = 0; x < box.width; ++x, src += 4, out += 3) {
      const float coverage = src[3];
      if (coverage <= 0.0f) continue;
      const float rest = 1.0f - std::min(coverage, 1.0f);
      for (int c = 0; c < 3; ++c)
        out[c] = LinearToSrgb8(to_srgb, src[c] + rest * to_linear[out[c]]);
    }
  }
  return true;
}

}  // namespace pintag::scene::detail
