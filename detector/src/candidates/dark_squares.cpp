#include "candidates/dark_squares.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "candidates/borders.hpp"
#include "homography.hpp"
#include "pintag/codec/geometry.hpp"

namespace pintag::stage {
namespace {

// Half-resolution local threshold, from the darkest and brightest value in the 3 × 3 tiles of
// 4 × 4 px around a pixel's tile (12 to 16 half-px: a small tag with its quiet zone): the pixel
// is dark when below their midpoint, and only where they differ by kMinContrast. A tag's black
// against its white quiet zone differs by more, even under hard light; most of a photograph's
// texture does not, and gives no outlines to trace. (On the seed-1 sweep, 40 levels gave 348
// outlines a frame to look at and 206 tags read from the squares; 100 gave 98 and 210, and cut
// the stage from 2.5 to 0.8 ms.)
constexpr int kTilePx = 4;
constexpr int kMinContrast = 100;
constexpr double kMinSolidity = 0.7;
// Contour area over bounding-box area: a square fills half its box turned 45°, and less when
// also seen steeply.
constexpr double kMinBoxFill = 0.35;
// max(R, G, B), 8-bit levels, by which every element must outshine the black: loosely on the
// rough quad (3 × 3 means, the square's centre only), then on the refined one.
constexpr int kRoughPatternMargin = 10;
constexpr int kPatternMargin = 15;
// Least distance (px) of a margin point the refined test reads as black from the middle of the
// edge beside it: nearer, blur brings in the quiet zone's white. The points lie 0.08 of a side
// inside, so on squares under about 37 px a side no margin is read even face-on (and fewer on
// steep ones); there the elements are held against the centre alone, and the readers decide.
constexpr double kMinMarginInsetPx = 3;

int MaxChannelAt(const cv::Mat& bgr, cv::Point2d p, int radius) {
  // A degenerate quad's homography can put a point anywhere: nothing there counts as bright.
  if (!(std::abs(p.x) < 1e6 && std::abs(p.y) < 1e6)) return 0;
  const int cx = static_cast<int>(std::lround(p.x)), cy = static_cast<int>(std::lround(p.y));
  int sum = 0, count = 0;
  for (int y = std::max(0, cy - radius); y <= std::min(bgr.rows - 1, cy + radius); ++y) {
    for (int x = std::max(0, cx - radius); x <= std::min(bgr.cols - 1, cx + radius); ++x) {
      const std::uint8_t* px = bgr.ptr<std::uint8_t>(y) + 3 * static_cast<std::ptrdiff_t>(x);
      sum += std::max({px[0], px[1], px[2]});
      ++count;
    }
  }
  return count > 0 ? sum / count : 0;
}

// The weakest element's brightness over the brightest black point's. On a rough quad the points
// are placed by bilinear interpolation of the corners (perspective within a small square moves
// them by less than the quad's own error) and averaged over 3 × 3 pixels; on a refined one
// through its homography.
int PatternContrast(const cv::Mat& bgr, const Quad& quad, bool rough) {
  cv::Matx33d h;
  if (!rough) h = HomographyFromQuad(quad);
  const auto at = [&](const geometry::Point& p) {
    if (!rough) return Apply(h, p.x, p.y);
    return quad[0] * ((1 - p.x) * (1 - p.y)) + quad[1] * (p.x * (1 - p.y)) + quad[2] * (p.x * p.y) +
           quad[3] * ((1 - p.x) * p.y);
  };
  const int radius = rough ? 1 : 0;
  int elements = 255;
  for (const geometry::Point& c : geometry::kElementCentres) {
    elements = std::min(elements, MaxChannelAt(bgr, at(c), radius));
  }
  // The centre, and (once refined) the middle of each margin between the elements and the edge
  // that lies far enough inside the edge to stay black under blur (measured along the square's
  // centre line, from the middle of the edge beside it: the margin point moved onto the edge).
  int black = MaxChannelAt(bgr, at({0.5, 0.5}), radius);
  if (rough) return elements - black;
  static constexpr std::array<geometry::Point, 4> kMargins = {
      {{0.5, 0.08}, {0.92, 0.5}, {0.5, 0.92}, {0.08, 0.5}}};
  for (const geometry::Point& m : kMargins) {
    const geometry::Point edge = {m.x == 0.5 ? 0.5 : std::round(m.x),
                                  m.y == 0.5 ? 0.5 : std::round(m.y)};
    const cv::Point2d p = at(m);
    if (cv::norm(p - at(edge)) < kMinMarginInsetPx) continue;
    black = std::max(black, MaxChannelAt(bgr, p, radius));
  }
  return elements - black;
}

// 255 where `image` is dark for its neighbourhood (see kTilePx), else 0. Vectorised: this runs
// on every frame.
cv::Mat LocalDark(const cv::Mat& image) {
  static_assert(kTilePx == 4, "the vector loops take tiles as groups of 4 bytes");
  const int tiles_x = image.cols / kTilePx, tiles_y = image.rows / kTilePx;
  cv::Mat dark(image.size(), CV_8U, cv::Scalar(0));
  if (tiles_x < 3 || tiles_y < 3) return dark;
  // Per tile: the darkest and brightest value (the last partial tile row and column are left
  // out; they stay "not dark").
  cv::Mat lo(tiles_y, tiles_x, CV_8U), hi(tiles_y, tiles_x, CV_8U);
  std::vector<std::uint8_t> column_lo(static_cast<std::size_t>(tiles_x) * kTilePx),
      column_hi(column_lo.size());
  const int width = tiles_x * kTilePx;
  for (int ty = 0; ty < tiles_y; ++ty) {
    const std::uint8_t* rows[kTilePx];
    for (int k = 0; k < kTilePx; ++k) rows[k] = image.ptr<std::uint8_t>(ty * kTilePx + k);
    int x = 0;
#if CV_SIMD128
    for (; x + 16 <= width; x += 16) {
      cv::v_uint8x16 a = cv::v_load(rows[0] + x), b = cv::v_load(rows[1] + x),
                     c = cv::v_load(rows[2] + x), d = cv::v_load(rows[3] + x);
      cv::v_store(column_lo.data() + x, cv::v_min(cv::v_min(a, b), cv::v_min(c, d)));
      cv::v_store(column_hi.data() + x, cv::v_max(cv::v_max(a, b), cv::v_max(c, d)));
    }
#endif
    for (; x < width; ++x) {
      column_lo[x] = std::min({rows[0][x], rows[1][x], rows[2][x], rows[3][x]});
      column_hi[x] = std::max({rows[0][x], rows[1][x], rows[2][x], rows[3][x]});
    }
    std::uint8_t* tile_lo = lo.ptr<std::uint8_t>(ty);
    std::uint8_t* tile_hi = hi.ptr<std::uint8_t>(ty);
    for (int t = 0; t < tiles_x; ++t) {
      const std::uint8_t* l = column_lo.data() + static_cast<std::ptrdiff_t>(kTilePx) * t;
      const std::uint8_t* h = column_hi.data() + static_cast<std::ptrdiff_t>(kTilePx) * t;
      tile_lo[t] = std::min({l[0], l[1], l[2], l[3]});
      tile_hi[t] = std::max({h[0], h[1], h[2], h[3]});
    }
  }
  // Each tile's extremes over its 3 × 3 neighbourhood, then its threshold: the midpoint, rounded
  // up (v < mid exactly when 2 v < low + high), or 0 (nothing is dark) without contrast.
  const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_RECT, {3, 3});
  cv::erode(lo, lo, kernel, {-1, -1}, 1, cv::BORDER_REPLICATE);
  cv::dilate(hi, hi, kernel, {-1, -1}, 1, cv::BORDER_REPLICATE);
  std::vector<std::uint8_t> threshold(static_cast<std::size_t>(width));
  for (int ty = 0; ty < tiles_y; ++ty) {
    const std::uint8_t* tile_lo = lo.ptr<std::uint8_t>(ty);
    const std::uint8_t* tile_hi = hi.ptr<std::uint8_t>(ty);
    for (int t = 0; t < tiles_x; ++t) {
      const int low = tile_lo[t], high = tile_hi[t];
      const auto mid =
          static_cast<std::uint8_t>(high - low >= kMinContrast ? (low + high + 1) / 2 : 0);
      std::fill_n(threshold.data() + static_cast<std::ptrdiff_t>(kTilePx) * t, kTilePx, mid);
    }
    for (int k = 0; k < kTilePx; ++k) {
      const int y = ty * kTilePx + k;
      const std::uint8_t* row = image.ptr<std::uint8_t>(y);
      std::uint8_t* out = dark.ptr<std::uint8_t>(y);
      int x = 0;
#if CV_SIMD128
      for (; x + 16 <= width; x += 16) {
        cv::v_store(out + x, cv::v_reinterpret_as_u8(cv::v_load(row + x) <
                                                     cv::v_load(threshold.data() + x)));
      }
#endif
      for (; x < width; ++x) out[x] = row[x] < threshold[x] ? 255 : 0;
    }
  }
  return dark;
}

// A solid, four-sided convex outline from a contour's hull, in half-resolution px.
bool FourSided(const std::vector<cv::Point>& contour, Quad* quad) {
  std::vector<cv::Point> hull;
  cv::convexHull(contour, hull);
  const double hull_area = cv::contourArea(hull);
  if (hull_area <= 0 || cv::contourArea(contour) < kMinSolidity * hull_area) return false;
  const double perimeter = cv::arcLength(hull, true);
  return QuadFromHull(hull, {0.04 * perimeter, 0.07 * perimeter, 0.1 * perimeter}, quad);
}

cv::Point2d Centre(const Quad& q) {
  return (q[0] + q[1] + q[2] + q[3]) / 4;
}

}  // namespace

bool ElementsOutshineCentre(const cv::Mat& bgr, const Quad& quad) {
  return PatternContrast(bgr, quad, /*rough=*/true) >= kRoughPatternMargin;
}

std::vector<Quad> FindDarkSquares(const cv::Mat& bgr, const cv::Mat& dark_half,
                                  const DarkSquareLimits& limits,
                                  const std::function<bool(cv::Point2d)>& skip) {
  std::vector<Quad> squares;
  if (dark_half.empty()) return squares;
  CV_Assert(dark_half.type() == CV_8UC1 && dark_half.cols == bgr.cols / 2 &&
            dark_half.rows == bgr.rows / 2);
  cv::Mat dark = LocalDark(dark_half);
  const std::vector<std::vector<cv::Point>> contours = TraceBorders(dark, BorderSet::kAll);

  const auto found_already = [&](cv::Point2d p) {
    return std::any_of(squares.begin(), squares.end(),
                       [&](const Quad& q) { return QuadContains(q, p); });
  };
  const cv::Rect frame(0, 0, bgr.cols, bgr.rows);
  for (const std::vector<cv::Point>& contour : contours) {
    if (contour.size() < 4) continue;
    const cv::Rect box = cv::boundingRect(contour);
    const int longest = 2 * std::max(box.width, box.height);
    if (longest < limits.min_square_px / 2 || longest > limits.max_side_px) continue;
    if (cv::contourArea(contour) < kMinBoxFill * box.area()) continue;
    Quad rough;
    if (!FourSided(contour, &rough)) continue;
    // Half-resolution pixel (x, y) covers full-resolution pixels 2x and 2x + 1.
    for (cv::Point2d& p : rough) p = 2.0 * p + cv::Point2d(0.5, 0.5);
    const cv::Point2d rough_centre = Centre(rough);
    if (skip && skip(rough_centre)) continue;
    // A tag gives several outlines (its square, and dark shapes inside it): one square each.
    if (found_already(rough_centre)) continue;
    if (!ElementsOutshineCentre(bgr, rough)) continue;

    // At full resolution: the outline again (the half-resolution one is a pixel or two off), its
    // corners refined on the square's edges, the pattern checked on them. The region holds more
    // than this outline: the square kept must be the one outlined here (its centre inside the
    // rough quad), not a neighbour already found or decoded.
    const cv::Rect roi =
        cv::Rect(2 * box.x - 8, 2 * box.y - 8, 2 * box.width + 16, 2 * box.height + 16) & frame;
    const cv::Mat region = MinChannel(bgr, roi);
    for (Quad quad : FindQuads(region, roi.tl(), limits.min_square_px, nullptr,
                               /*close_gaps=*/false)) {
      if (!RefineCorners(region, roi.tl(), &quad)) continue;
      const cv::Point2d centre = Centre(quad);
      if (!QuadContains(rough, centre) || (skip && skip(centre)) || found_already(centre)) continue;
      if (PatternContrast(bgr, quad, /*rough=*/false) < kPatternMargin) continue;
      squares.push_back(quad);
      break;
    }
  }
  return squares;
}

}  // namespace pintag::stage
