#include "quads.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace pintag::stage {
namespace {

bool ToQuad(const std::vector<cv::Point>& polygon, Quad* quad) {
  if (polygon.size() != 4 || !cv::isContourConvex(polygon)) return false;
  for (int i = 0; i < 4; ++i) (*quad)[i] = cv::Point2d(polygon[i].x, polygon[i].y);
  if (SignedArea2(*quad) < 0) std::reverse(quad->begin(), quad->end());
  return true;
}

double MinSide(const Quad& q) {
  double side = 1e18;
  for (int i = 0; i < 4; ++i) side = std::min(side, cv::norm(q[(i + 1) % 4] - q[i]));
  return side;
}

}  // namespace

double SignedArea2(const Quad& q) {
  double s = 0;
  for (int i = 0; i < 4; ++i) s += q[i].x * q[(i + 1) % 4].y - q[(i + 1) % 4].x * q[i].y;
  return s;
}

cv::Mat MinChannel(const cv::Mat& bgr, const cv::Rect& roi) {
  cv::Mat out(roi.size(), CV_8U);
  for (int y = 0; y < roi.height; ++y) {
    const std::uint8_t* p =
        bgr.ptr<std::uint8_t>(roi.y + y) + 3 * static_cast<std::ptrdiff_t>(roi.x);
    std::uint8_t* o = out.ptr<std::uint8_t>(y);
    for (int x = 0; x < roi.width; ++x, p += 3) o[x] = std::min({p[0], p[1], p[2]});
  }
  return out;
}

std::vector<Quad> FindQuads(const cv::Mat& dark, cv::Point origin, double min_side_px,
                            const std::vector<cv::Point2d>* anchors, bool close_gaps,
                            int min_anchors_inside) {
  cv::Mat binary;
  cv::threshold(dark, binary, 0, 255, cv::THRESH_BINARY_INV | cv::THRESH_OTSU);
  if (close_gaps) {
    cv::morphologyEx(binary, binary, cv::MORPH_CLOSE,
                     cv::getStructuringElement(cv::MORPH_RECT, {3, 3}));
  }
  // Outer boundaries of every dark component, including those inside holes of others (a tag on
  // dark ground sits inside the hole its quiet zone makes).
  std::vector<std::vector<cv::Point>> contours;
  std::vector<cv::Vec4i> hierarchy;
  cv::findContours(binary, contours, hierarchy, cv::RETR_CCOMP, cv::CHAIN_APPROX_NONE);
  std::vector<Quad> quads;
  const double min_area = min_side_px * min_side_px * 0.25;
  for (std::size_t c = 0; c < contours.size(); ++c) {
    const auto& contour = contours[c];
    if (hierarchy[c][3] >= 0 || contour.size() < 8) continue;
    if (anchors) {
      const cv::Rect box = cv::boundingRect(contour) + origin;
      int inside = 0;
      for (const cv::Point2d& p : *anchors) inside += box.contains(cv::Point(p));
      if (inside < min_anchors_inside) continue;
    }
    const double area = cv::contourArea(contour);
    if (area < min_area) continue;
    const double perimeter = cv::arcLength(contour, true);
    // The hull: a light cover over an element can notch the square's outline, and the tag's
    // outline is convex anyway.
    std::vector<cv::Point> hull, polygon;
    cv::convexHull(contour, hull);
    Quad quad;
    bool found = false;
    for (double eps : {0.02, 0.035, 0.05}) {
      cv::approxPolyDP(hull, polygon, eps * perimeter, true);
      if ((found = ToQuad(polygon, &quad))) break;
    }
    if (!found || MinSide(quad) < min_side_px * 0.3) continue;
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
