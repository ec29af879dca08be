#include "pyramid_warp.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "pintag/scene/rng.hpp"
#include "srgb.hpp"

namespace pintag::scene::detail {
namespace {

cv::Point2d Map(const cv::Matx33d& h, double x, double y, double* w = nullptr) {
  const double d = h(2, 0) * x + h(2, 1) * y + h(2, 2);
  if (w != nullptr) *w = d;
  return {(h(0, 0) * x + h(0, 1) * y + h(0, 2)) / d, (h(1, 0) * x + h(1, 1) * y + h(1, 2)) / d};
}

/// Texels per frame pixel at frame point (x, y): the geometric mean of the two directions' scale,
/// i.e. the square root of the Jacobian's determinant.
double MeanStretch(const cv::Matx33d& texture_from_image, double x, double y) {
  const cv::Point2d p = Map(texture_from_image, x, y);
  const cv::Point2d px = Map(texture_from_image, x + 1, y);
  const cv::Point2d py = Map(texture_from_image, x, y + 1);
  return std::sqrt(std::abs((px.x - p.x) * (py.y - p.y) - (py.x - p.x) * (px.y - p.y)));
}

/// The print's colours: linear light through the mix, the lift and the paper, back to sRGB.
cv::Mat Print(const cv::Mat& bgr, const PrintErrors& print) {
  const auto& to_linear = SrgbToLinearTable();
  const std::uint8_t* to_srgb = LinearToSrgbTable();
  cv::Mat out(bgr.size(), CV_8UC3);
  for (int y = 0; y < bgr.rows; ++y) {
    const auto* src = bgr.ptr<cv::Vec3b>(y);
    auto* dst = out.ptr<cv::Vec3b>(y);
    for (int x = 0; x < bgr.cols; ++x) {
      const cv::Vec3d linear(to_linear[src[x][0]], to_linear[src[x][1]], to_linear[src[x][2]]);
      const cv::Vec3d mixed = print.mix * linear;
      for (int c = 0; c < 3; ++c) {
        const double ink = print.black_lift + (1 - print.black_lift) * mixed[c];
        dst[x][c] = LinearToSrgb8(to_srgb, static_cast<float>(print.paper[c] * ink));
      }
    }
  }
  return out;
}

}  // namespace

PrintErrors PrintErrors::Random(std::uint64_t seed) {
  Rng rng(seed ^ 0x5052494E54ULL);
  PrintErrors p;
  for (int r = 0; r < 3; ++r) {
    double row_sum = 0;
    for (int c = 0; c < 3; ++c) {
      p.mix(r, c) = r == c ? rng.uniform(0.95, 1.0) : rng.uniform(-0.02, 0.04);
      row_sum += p.mix(r, c);
    }
    for (int c = 0; c < 3; ++c) p.mix(r, c) /= std::max(1.0, row_sum);  // white stays ≤ 1
    p.paper[r] = rng.uniform(0.92, 1.0);
  }
  p.black_lift = rng.uniform(0.005, 0.03);
  return p;
}

bool WarpThroughPyramid(cv::Mat& frame, const MarkerTexture& texture,
                        const cv::Matx33d& image_from_texture, const PrintErrors& print) {
  const double tw = texture.bgr.cols, th = texture.bgr.rows;
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

  // The level: texels per frame pixel at the square's centre, rounded down to a power of two.
  const cv::Matx33d texture_from_image = image_from_texture.inv();
  const auto& c = texture.square_corners_px;
  const cv::Point2d centre = Map(image_from_texture, (c[0].x + c[2].x) / 2, (c[0].y + c[2].y) / 2);
  const double stretch = MeanStretch(texture_from_image, centre.x, centre.y);
  int level = 0;
  while (stretch >= (2 << level) && (texture.bgr.cols >> (level + 1)) >= 8) ++level;
  cv::Mat reduced = texture.bgr;
  if (level > 0) {
    const cv::Size size(std::max(1, texture.bgr.cols >> level),
                        std::max(1, texture.bgr.rows >> level));
    cv::resize(texture.bgr, reduced, size, 0, 0, cv::INTER_AREA);
  }
  cv::Mat printed = Print(reduced, print);
  cv::Mat with_alpha;
  cv::cvtColor(printed, with_alpha, cv::COLOR_BGR2BGRA);  // alpha 255: coverage after the warp

  // Level coordinates: u_l = (u + 0.5) · sx − 0.5.
  const double sx = static_cast<double>(reduced.cols) / texture.bgr.cols;
  const double sy = static_cast<double>(reduced.rows) / texture.bgr.rows;
  const cv::Matx33d to_level(sx, 0, 0.5 * sx - 0.5, 0, sy, 0.5 * sy - 0.5, 0, 0, 1);
  const cv::Matx33d box_to_frame(1, 0, x0, 0, 1, y0, 0, 0, 1);
  const cv::Matx33d level_from_box = to_level * texture_from_image * box_to_frame;
  const cv::Size box(x1 - x0 + 1, y1 - y0 + 1);
  cv::Mat warped;
  cv::warpPerspective(with_alpha, warped, cv::Mat(level_from_box), box,
                      cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_CONSTANT,
                      cv::Scalar::all(0));
  for (int y = 0; y < box.height; ++y) {
    const auto* src = warped.ptr<cv::Vec4b>(y);
    auto* out = frame.ptr<cv::Vec3b>(y + y0) + x0;
    for (int x = 0; x < box.width; ++x) {
      const int a = src[x][3];
      if (a == 0) continue;
      for (int k = 0; k < 3; ++k) {
        // The warp mixed the border's zeros into colour and coverage alike: premultiplied.
        out[x][k] = static_cast<std::uint8_t>(
            std::min(255, src[x][k] + (out[x][k] * (255 - a) + 127) / 255));
      }
    }
  }
  return true;
}

}  // namespace pintag::scene::detail
