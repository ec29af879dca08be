// The outline and caption drawn on overlays and debug images.

#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "pintag/detector/tag_outline.hpp"

namespace pintag {
namespace {

/// A detection whose square has its first corner at (x, y), 40 px a side.
Detection SquareAt(double x, double y) {
  Detection d;
  d.corners = {Point2{x, y}, Point2{x + 40, y}, Point2{x + 40, y + 40}, Point2{x, y + 40}};
  return d;
}

/// Pixels of the caption's white: the outline is drawn in another colour, the photo is grey.
int WhitePixels(const cv::Mat& image) {
  int white = 0;
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      const cv::Vec3b& p = image.at<cv::Vec3b>(y, x);
      if (p[0] > 250 && p[1] > 250 && p[2] > 250) ++white;
    }
  }
  return white;
}

// A caption above a tag near an edge ran off the photo ("key 102 u…" on a scanner's overlay);
// it is moved inside instead, so it shows whole wherever the tag lies.
TEST(TagOutline, ACaptionNearAnEdgeOfThePhotoShowsWhole) {
  const std::string caption = "110001 unknown office";
  cv::Mat open(400, 800, CV_8UC3, cv::Scalar(128, 128, 128));
  DrawTagOutline(open, SquareAt(300, 200), cv::Scalar(0, 220, 255), caption);
  const int whole = WhitePixels(open);
  ASSERT_GT(whole, 100);
  for (const auto& [x, y] : {std::pair{760.0, 200.0}, std::pair{300.0, 2.0}, std::pair{2.0, 2.0},
                             std::pair{760.0, 356.0}}) {
    cv::Mat near_edge(400, 800, CV_8UC3, cv::Scalar(128, 128, 128));
    DrawTagOutline(near_edge, SquareAt(x, y), cv::Scalar(0, 220, 255), caption);
    EXPECT_EQ(WhitePixels(near_edge), whole) << "first corner at " << x << ", " << y;
  }
}

}  // namespace
}  // namespace pintag
