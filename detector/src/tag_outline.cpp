#include "pintag/detector/tag_outline.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace pintag {
namespace {

cv::Point ToPixel(const Point2& p) {
  return {static_cast<int>(std::lround(p.x)), static_cast<int>(std::lround(p.y))};
}

double Scale(const cv::Mat& image) {
  return std::max(1.0, std::max(image.cols, image.rows) / 1200.0);
}

}  // namespace

int OutlineThickness(const cv::Mat& image) {
  return static_cast<int>(std::lround(2 * Scale(image)));
}

void DrawTagOutline(cv::Mat& image, const Detection& detection, const cv::Scalar& colour,
                    const std::string& caption) {
  const int thickness = OutlineThickness(image);
  const auto& corners = detection.corners;
  for (std::size_t c = 0; c < corners.size(); ++c) {
    cv::line(image, ToPixel(corners[c]), ToPixel(corners[(c + 1) % corners.size()]), colour,
             thickness, cv::LINE_AA);
  }
  cv::circle(image, ToPixel(corners[0]), 3 * thickness, colour, -1, cv::LINE_AA);
  if (caption.empty()) return;
  // White on a black halo: readable on any photo.
  const double font = 0.7 * Scale(image);
  // Above the first corner, moved inside the photo where it would run off an edge (a tag near
  // the right edge had its caption cut to "key 102 u…").
  int baseline = 0;
  const cv::Size text =
      cv::getTextSize(caption, cv::FONT_HERSHEY_SIMPLEX, font, 3 * thickness, &baseline);
  const cv::Point wanted = ToPixel(corners[0]) + cv::Point(0, -5 * thickness);
  const int margin = 2 * thickness;
  const cv::Point at(
      std::clamp(wanted.x, margin, std::max(margin, image.cols - text.width - margin)),
      std::clamp(wanted.y, text.height + margin,
                 std::max(text.height + margin, image.rows - baseline - margin)));
  cv::putText(image, caption, at, cv::FONT_HERSHEY_SIMPLEX, font, {0, 0, 0}, 3 * thickness,
              cv::LINE_AA);
  cv::putText(image, caption, at, cv::FONT_HERSHEY_SIMPLEX, font, {255, 255, 255}, thickness,
              cv::LINE_AA);
}

}  // namespace pintag
