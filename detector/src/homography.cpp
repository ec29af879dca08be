#include "homography.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace pintag::stage {
namespace {

// Linear light of an 8-bit sRGB code. Blur and pixel integration happen in linear light, before
// the camera's tone curve, so edges are located on linear values: there a blurred step crosses
// halfway exactly at the edge.
const std::array<float, 256>& LinearTable() {
  static const std::array<float, 256> table = [] {
    std::array<float, 256> t{};
    for (int c = 0; c < 256; ++c) {
      const double v = c / 255.0;
      t[c] = static_cast<float>(v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4));
    }
    return t;
  }();
  return table;
}

/// Bilinear interpolation of linear light; −1 outside the image.
double Bilinear(const cv::Mat& img, double x, double y) {
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  if (x0 < 0 || y0 < 0 || x0 + 1 >= img.cols || y0 + 1 >= img.rows) return -1;
  const auto& lin = LinearTable();
  const double fx = x - x0, fy = y - y0;
  const std::uint8_t* r0 = img.ptr<std::uint8_t>(y0) + x0;
  const std::uint8_t* r1 = img.ptr<std::uint8_t>(y0 + 1) + x0;
  return (lin[r0[0]] * (1 - fx) + lin[r0[1]] * fx) * (1 - fy) +
         (lin[r1[0]] * (1 - fx) + lin[r1[1]] * fx) * fy;
}

// Edge points along the side from a to b (clockwise, so the tag is on the right-hand side, the
// outward normal on the left), in region coordinates.
std::vector<cv::Point2f> EdgePoints(const cv::Mat& dark, cv::Point2d a, cv::Point2d b,
                                    double reach) {
  const cv::Point2d d = b - a;
  const double length = cv::norm(d);
  const cv::Point2d along = d / length;
  const cv::Point2d outward(along.y, -along.x);
  const int samples = std::clamp(static_cast<int>(length / 1.5), 6, 48);
  constexpr double kStep = 0.25;
  const int steps = static_cast<int>(reach / kStep);
  std::vector<double> profile(2 * steps + 1);
  std::vector<cv::Point2f> points;
  for (int k = 0; k < samples; ++k) {
    const double t = 0.12 + 0.76 * (k + 0.5) / samples;
    const cv::Point2d q = a + d * t;
    bool inside = true;
    for (int s = -steps; s <= steps && inside; ++s) {
      const cv::Point2d p = q + outward * (s * kStep);
      profile[s + steps] = Bilinear(dark, p.x, p.y);
      inside = profile[s + steps] >= 0;
    }
    if (!inside) continue;
    const int quarter = std::max(1, steps / 3);
    double lo = 0, hi = 0;
    for (int s = 0; s < quarter; ++s) {
      lo += profile[s];
      hi += profile[2 * steps - s];
    }
    lo /= quarter;
    hi /= quarter;
    // On dark ground the quiet zone is a light band with dark beyond it: its brightest stretch
    // outside the edge is the white level, not the far end of the profile.
    for (int s = steps; s + 2 <= 2 * steps; ++s) {
      hi = std::max(hi, (profile[s] + profile[s + 1] + profile[s + 2]) / 3);
    }
    if (hi - lo < 0.08 || hi < 2 * lo) continue;  // no clear dark-to-white step here
    const double level = (lo + hi) / 2;
    // The crossing nearest the expected edge (the middle of the profile).
    double best = 1e9;
    for (int s = 0; s < 2 * steps; ++s) {
      if ((profile[s] < level) == (profile[s + 1] < level)) continue;
      const double frac = (level - profile[s]) / (profile[s + 1] - profile[s]);
      const double offset = (s + frac - steps) * kStep;
      if (std::abs(offset) < std::abs(best)) best = offset;
    }
    if (best > 1e8) continue;
    const cv::Point2d p = q + outward * best;
    points.emplace_back(static_cast<float>(p.x), static_cast<float>(p.y));
  }
  return points;
}

bool Intersect(const cv::Vec4f& l1, const cv::Vec4f& l2, cv::Point2d* out) {
  const double d1x = l1[0], d1y = l1[1], d2x = l2[0], d2y = l2[1];
  const double det = d1x * d2y - d1y * d2x;
  if (std::abs(det) < 1e-9) return false;
  const double px = l2[2] - l1[2], py = l2[3] - l1[3];
  const double t = (px * d2y - py * d2x) / det;
  *out = {l1[2] + t * d1x, l1[3] + t * d1y};
  return true;
}

}  // namespace

namespace {

// One line fit per side, the edge points searched up to `wide` ? 8 px (8 % of the side, at least
// 2.5) : 2.5 px from the current side; `q` becomes the lines' corners. False when a side has too
// few edge points or two lines do not meet.
bool FitSides(const cv::Mat& dark, bool wide, Quad* q) {
  std::array<cv::Vec4f, 4> lines;
  for (int i = 0; i < 4; ++i) {
    const cv::Point2d a = (*q)[i], b = (*q)[(i + 1) % 4];
    const double length = cv::norm(b - a);
    const double reach = wide ? std::clamp(0.08 * length, 2.5, 8.0) : 2.5;
    const std::vector<cv::Point2f> points = EdgePoints(dark, a, b, reach);
    if (points.size() < 4) return false;
    cv::fitLine(points, lines[i], cv::DIST_HUBER, 0, 0.01, 0.01);
  }
  for (int i = 0; i < 4; ++i) {
    // Corner i is where the edge into it (i−1 → i) meets the edge out of it (i → i+1).
    if (!Intersect(lines[(i + 3) % 4], lines[i], &(*q)[i])) return false;
  }
  return true;
}

// From `fitted` (the start after one wide fit), `more_wide` more wide fits and a narrow one; the
// result replaces `*start` when no corner moved more than `max_move` px from it in all.
bool Refine(const cv::Mat& dark, Quad fitted, int more_wide, double max_move, Quad* start) {
  for (int pass = 0; pass <= more_wide; ++pass) {
    if (!FitSides(dark, pass < more_wide, &fitted)) return false;
  }
  for (int i = 0; i < 4; ++i) {
    if (cv::norm(fitted[i] - (*start)[i]) > max_move) return false;  // the fit went astray
  }
  if (SignedArea2(fitted) <= 0) return false;
  *start = fitted;
  return true;
}

}  // namespace

bool RefineCorners(const cv::Mat& dark, cv::Point origin, Quad* quad) {
  Quad local = *quad;
  for (cv::Point2d& p : local) p -= cv::Point2d(origin);
  double mean_side = 0;
  for (int i = 0; i < 4; ++i) mean_side += cv::norm(local[(i + 1) % 4] - local[i]) / 4;
  // Usually the rough quad is within a pixel or two: one wide pass and one narrow. Where
  // something covers part of the outline it can be further off: then two wide passes (each fit
  // Huber-weighted over the edge points found near the previous line) and a narrow one. Both
  // begin with the same wide pass, fitted once (most candidates that are not tags fail there).
  Quad fitted = local;
  if (!FitSides(dark, /*wide=*/true, &fitted)) return false;
  if (!Refine(dark, fitted, 0, 8, &local) && !Refine(dark, fitted, 1, 0.2 * mean_side, &local)) {
    return false;
  }
  for (int i = 0; i < 4; ++i) (*quad)[i] = local[i] + cv::Point2d(origin);
  return true;
}

cv::Matx33d HomographyFromQuad(const Quad& quad) {
  const cv::Point2f src[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  cv::Point2f dst[4];
  for (int i = 0; i < 4; ++i)
    dst[i] = cv::Point2f(static_cast<float>(quad[i].x), static_cast<float>(quad[i].y));
  // getPerspectiveTransform in double from float points loses little: tag units are exact.
  const cv::Mat h = cv::getPerspectiveTransform(src, dst, cv::DECOMP_LU);
  return cv::Matx33d(h);
}

Quad RotateQuad(const Quad& quad, int first) {
  Quad out;
  for (int i = 0; i < 4; ++i) out[i] = quad[(i + first) % 4];
  return out;
}

cv::Point2d Apply(const cv::Matx33d& h, double u, double v) {
  const cv::Vec3d p = h * cv::Vec3d(u, v, 1);
  return {p[0] / p[2], p[1] / p[2]};
}

double MeanSidePx(const cv::Matx33d& tag_to_image) {
  return MeanSidePx(Quad{Apply(tag_to_image, 0, 0), Apply(tag_to_image, 1, 0),
                         Apply(tag_to_image, 1, 1), Apply(tag_to_image, 0, 1)});
}

double ShortExtentPx(const cv::Matx33d& tag_to_image) {
  const cv::Matx33d& h = tag_to_image;
  constexpr double kCentre = 0.5;
  const double w = h(2, 0) * kCentre + h(2, 1) * kCentre + h(2, 2);
  const cv::Point2d c = Apply(h, kCentre, kCentre);
  // d(x, y)/d(u, v) of x = (h00 u + h01 v + h02) / w, and the same for y.
  const double a = (h(0, 0) - c.x * h(2, 0)) / w, b = (h(0, 1) - c.x * h(2, 1)) / w;
  const double d = (h(1, 0) - c.y * h(2, 0)) / w, e = (h(1, 1) - c.y * h(2, 1)) / w;
  // Singular values of [[a, b], [d, e]]: σ² = (S ∓ √(S² − 4 det²)) / 2, S the squared entries.
  const double sum = a * a + b * b + d * d + e * e, det = a * e - b * d;
  const double root = std::sqrt(std::max(0.0, sum * sum - 4 * det * det));
  return std::sqrt(std::max(0.0, (sum - root) / 2));
}

}  // namespace pintag::stage
