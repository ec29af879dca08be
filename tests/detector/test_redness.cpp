// Stage 1: the redness pass finds exactly the tag's red disks.

#include <gtest/gtest.h>

#include "candidates/redness.hpp"
#include "pintag/codec/cielab.hpp"
#include "pintag/codec/geometry.hpp"
#include "pintag/codec/tag_raster.hpp"

namespace pintag::stage {
namespace {

cv::Mat ToBgr(const RgbImage& image) {
  cv::Mat bgr(image.height, image.width, CV_8UC3);
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      const Rgb8 c = image.at(x, y);
      bgr.at<cv::Vec3b>(y, x) = {c.b, c.g, c.r};
    }
  }
  return bgr;
}

TEST(Redness, MarksTheRedDisksOfARenderedTag) {
  const TagRaster raster = RenderTagRaster(TagKey(4321), {200, 4});
  const cv::Mat bgr = ToBgr(raster.image);
  const cv::Mat mask = RednessMask(bgr, {});
  int wrong = 0, red = 0;
  for (int y = 0; y < mask.rows; ++y) {
    for (int x = 0; x < mask.cols; ++x) {
      // Pixels straddling a boundary are mixtures; judge only pixels wholly inside one region.
      const double u = (x + 0.5 - raster.square_origin_px) / 200,
                   v = (y + 0.5 - raster.square_origin_px) / 200, h = 0.6 / 200;
      const auto cell = geometry::LocateCell(u, v);
      bool uniform = true;
      for (double du : {-h, h}) {
        for (double dv : {-h, h})
          uniform &= geometry::LocateCell(u + du, v + dv).region == cell.region;
      }
      if (!uniform) continue;
      const bool expect = cell.region == geometry::Region::kRed;
      red += expect;
      wrong += (mask.at<std::uint8_t>(y, x) != 0) != expect;
    }
  }
  EXPECT_GT(red, 4 * 3.14 * 20 * 20 * 0.8);
  EXPECT_EQ(wrong, 0);
}

TEST(Redness, RunsMatchTheMask) {
  cv::Mat bgr(40, 60, CV_8UC3, cv::Scalar(255, 255, 255));
  bgr(cv::Rect(5, 5, 10, 3)).setTo(cv::Scalar(3, 80, 249));
  bgr(cv::Rect(50, 30, 10, 2)).setTo(cv::Scalar(122, 13, 204));  // touches the right edge
  const RedRuns runs = FindRedRuns(bgr, {});
  ASSERT_EQ(runs.runs.size(), 5u);
  EXPECT_EQ(runs.runs[0].y, 5);
  EXPECT_EQ(runs.runs[0].x0, 5);
  EXPECT_EQ(runs.runs[0].x1, 14);
  EXPECT_EQ(runs.runs[4].x1, 59);
  EXPECT_EQ(cv::countNonZero(RunsToMask(runs)), 30 + 20);
}

TEST(Redness, SaturatedBlueAndSkinAreNotRed) {
  const RednessThresholds t;
  EXPECT_FALSE(IsRedPixel(0, 0, 255, t));      // a* = +79 but b* = −108
  EXPECT_FALSE(IsRedPixel(224, 172, 140, t));  // skin
  EXPECT_FALSE(IsRedPixel(255, 255, 255, t));
  EXPECT_TRUE(IsRedPixel(249, 80, 3, t));
  EXPECT_TRUE(IsRedPixel(204, 13, 122, t));
  EXPECT_TRUE(IsRedPixel(120, 10, 70, t));  // crimson at half exposure
}

}  // namespace
}  // namespace pintag::stage
