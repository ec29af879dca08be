#include "candidates/quads.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/imgproc.hpp>

#include "candidates/borders.hpp"

namespace pintag::stage {
namespace {

double MinSide(const Quad& q) {
  double side = 1e18;
  for (int i = 0; i < 4; ++i) side = std::min(side, cv::norm(q[(i + 1) % 4] - q[i]));
  return side;
}

// The number of boundary pixels a CHAIN_APPROX_NONE trace lists for the closed outline whose
// CHAIN_APPROX_SIMPLE trace is `corners`: each step of the trace moves to one of 8 neighbours, so
// a straight run between two kept points is as many steps as its longer coordinate difference.
std::size_t TracedPixels(const std::vector<cv::Point>& corners) {
  if (corners.size() < 2) return corners.size();
  std::size_t steps = 0;
  for (std::size_t i = 0; i < corners.size(); ++i) {
    const cv::Point d = corners[(i + 1) % corners.size()] - corners[i];
    steps += static_cast<std::size_t>(std::max(std::abs(d.x), std::abs(d.y)));
  }
  return steps;
}

// out[i] = the maximum (kMax) or minimum of a[i], b[i] and c[i], for i in [0, n).
template <bool kMax>
void Extreme3(const std::uint8_t* a, const std::uint8_t* b, const std::uint8_t* c, int n,
              std::uint8_t* out) {
  int i = 0;
#if CV_SIMD128
  for (; i + 16 <= n; i += 16) {
    const cv::v_uint8x16 va = cv::v_load(a + i), vb = cv::v_load(b + i), vc = cv::v_load(c + i);
    cv::v_store(out + i,
                kMax ? cv::v_max(cv::v_max(va, vb), vc) : cv::v_min(cv::v_min(va, vb), vc));
  }
#endif
  for (; i < n; ++i) {
    out[i] = kMax ? std::max(std::max(a[i], b[i]), c[i]) : std::min(std::min(a[i], b[i]), c[i]);
  }
}

// The 3 × 3 maximum (kMax) or minimum of `in` (CV_8U) into `out`, pixels outside the image left
// out: repeating the edge row or column changes neither. cv::morphologyEx does the same with
// a filter engine built for every call, and this stage calls it for every cluster.
template <bool kMax>
void Extreme3x3(const cv::Mat& in, cv::Mat& out) {
  out.create(in.size(), CV_8U);
  const int cols = in.cols;
  // column[1 + x]: the extreme of the three rows at x; column[0] and column[cols + 1] repeat the
  // edge columns.
  std::vector<std::uint8_t> column(static_cast<std::size_t>(cols) + 2);
  std::uint8_t* c = column.data() + 1;
  for (int y = 0; y < in.rows; ++y) {
    Extreme3<kMax>(in.ptr<std::uint8_t>(std::max(y - 1, 0)), in.ptr<std::uint8_t>(y),
                   in.ptr<std::uint8_t>(std::min(y + 1, in.rows - 1)), cols, c);
    c[-1] = c[0];
    c[cols] = c[cols - 1];
    Extreme3<kMax>(c - 1, c, c + 1, cols, out.ptr<std::uint8_t>(y));
  }
}

}  // namespace

void CloseGaps3x3(cv::Mat& binary) {
  cv::Mat dilated;
  Extreme3x3<true>(binary, dilated);
  Extreme3x3<false>(dilated, binary);
}

double MeanSidePx(const Quad& q) {
  double perimeter = 0;
  for (int i = 0; i < 4; ++i) perimeter += cv::norm(q[(i + 1) % 4] - q[i]);
  return perimeter / 4;
}

bool QuadContains(const Quad& quad, cv::Point2d p) {
  const std::vector<cv::Point2f> corners(quad.begin(), quad.end());
  return cv::pointPolygonTest(corners, cv::Point2f(p), false) >= 0;
}

bool SameSquare(const Quad& a, const Quad& b, double tolerance_px) {
  const double limit = tolerance_px * tolerance_px;
  for (std::size_t turn = 0; turn < 4; ++turn) {
    bool same = true;
    for (std::size_t i = 0; i < 4 && same; ++i) {
      const cv::Point2d d = a[i] - b[(i + turn) % 4];
      same = d.dot(d) <= limit;
    }
    if (same) return true;
  }
  return false;
}

bool QuadFromHull(const std::vector<cv::Point>& hull, std::initializer_list<double> tolerances_px,
                  Quad* quad) {
  std::vector<cv::Point> polygon;
  for (const double tolerance : tolerances_px) {
    cv::approxPolyDP(hull, polygon, tolerance, true);
    if (polygon.size() != 4 || !cv::isContourConvex(polygon)) continue;
    for (int i = 0; i < 4; ++i) (*quad)[i] = cv::Point2d(polygon[i].x, polygon[i].y);
    if (SignedArea2(*quad) < 0) std::reverse(quad->begin(), quad->end());
    return true;
  }
  return false;
}

double SignedArea2(const Quad& q) {
  double s = 0;
  for (int i = 0; i < 4; ++i) s += q[i].x * q[(i + 1) % 4].y - q[(i + 1) % 4].x * q[i].y;
  return s;
}

void MinChannelRow(const std::uint8_t* bgr, std::ptrdiff_t pixels, std::uint8_t* out) {
  std::ptrdiff_t x = 0;
#if CV_SIMD128
  for (; x + 16 <= pixels; x += 16) {
    cv::v_uint8x16 b, g, r;
    cv::v_load_deinterleave(bgr + 3 * x, b, g, r);
    cv::v_store(out + x, cv::v_min(cv::v_min(b, g), r));
  }
#endif
  for (; x < pixels; ++x) out[x] = std::min({bgr[3 * x], bgr[3 * x + 1], bgr[3 * x + 2]});
}

cv::Mat MinChannel(const cv::Mat& bgr, const cv::Rect& roi) {
  cv::Mat out(roi.size(), CV_8U);
  for (int y = 0; y < roi.height; ++y) {
    MinChannelRow(bgr.ptr<std::uint8_t>(roi.y + y) + 3 * static_cast<std::ptrdiff_t>(roi.x),
                  roi.width, out.ptr<std::uint8_t>(y));
  }
  return out;
}

std::vector<Quad> FindQuads(const cv::Mat& dark, cv::Point origin, double min_side_px,
                            const std::vector<cv::Point2d>* anchors, bool close_gaps,
                            int min_anchors_inside) {
  cv::Mat binary;
  cv::threshold(dark, binary, 0, 255, cv::THRESH_BINARY_INV | cv::THRESH_OTSU);
  if (close_gaps) CloseGaps3x3(binary);
  // Outer boundaries of every dark component, including those inside holes of others (a tag on
  // dark ground sits inside the hole its quiet zone makes). Only the ends of straight runs: the
  // hull, area and perimeter of an outline are those of its every pixel (the dropped ones lie on
  // the segments between), and hulls of long textured outlines cost a third of this function
  // when every pixel was kept.
  const std::vector<std::vector<cv::Point>> contours = TraceBorders(binary, BorderSet::kOuter);
  std::vector<Quad> quads;
  const double min_area = min_side_px * min_side_px * 0.25;
  for (const std::vector<cv::Point>& contour : contours) {
    if (TracedPixels(contour) < 8) continue;
    if (anchors) {
      const cv::Rect box = cv::boundingRect(contour) + origin;
      int inside = 0;
      for (const cv::Point2d& p : *anchors) inside += box.contains(cv::Point(p));
      if (inside < min_anchors_inside) continue;
    }
    const double area = cv::contourArea(contour);
    if (area < min_area) continue;
    // The hull: a light cover over an element can notch the square's outline, and the tag's
    // outline is convex anyway.
    std::vector<cv::Point> hull;
    cv::convexHull(contour, hull);
    const double perimeter = cv::arcLength(contour, true);
    Quad quad;
    if (!QuadFromHull(hull, {0.02 * perimeter, 0.035 * perimeter, 0.05 * perimeter}, &quad) ||
        MinSide(quad) < min_side_px * 0.3) {
      continue;
    }
    for (cv::Point2d& p : quad) p += cv::Point2d(origin);
    quads.push_back(quad);
  }
  return quads;
}

cv::Rect AnchorsRegion(const std::vector<cv::Point2d>& anchors, const cv::Rect& within) {
  if (anchors.empty()) return {};
  double spacing = 0;
  double x0 = anchors[0].x, y0 = anchors[0].y, x1 = x0, y1 = y0;
  for (std::size_t i = 0; i < anchors.size(); ++i) {
    double nearest = 1e300;
    for (std::size_t j = 0; j < anchors.size(); ++j) {
      if (j != i) nearest = std::min(nearest, cv::norm(anchors[i] - anchors[j]));
    }
    if (nearest < 1e300) spacing = std::max(spacing, nearest);
    x0 = std::min(x0, anchors[i].x), y0 = std::min(y0, anchors[i].y);
    x1 = std::max(x1, anchors[i].x), y1 = std::max(y1, anchors[i].y);
  }
  const double grow = 0.8 * spacing + 2;
  const cv::Point tl(static_cast<int>(std::floor(x0 - grow)),
                     static_cast<int>(std::floor(y0 - grow)));
  const cv::Point br(static_cast<int>(std::ceil(x1 + grow)) + 1,
                     static_cast<int>(std::ceil(y1 + grow)) + 1);
  return cv::Rect(tl, br) & within;
}

}  // namespace pintag::stage
