// Stage 2: blobs, their ellipse moments and the shape filter.

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "candidates/red_blobs.hpp"
#include "candidates/redness.hpp"

namespace pintag::stage {
namespace {

TEST(RedBlobs, EllipsesKeepTheirAxes) {
  cv::Mat mask(300, 300, CV_8U, cv::Scalar(0));
  cv::ellipse(mask, {{80, 80}, {40, 14}, 30}, 255, -1);  // a disk tilted ~70°
  cv::circle(mask, {200, 200}, 20, 255, -1);
  const auto blobs = FindRedBlobs(mask, {});
  ASSERT_EQ(blobs.size(), 2u);
  for (const RedBlob& b : blobs) {
    if (b.centroid.x < 150) {
      EXPECT_NEAR(b.centroid.x, 80, 0.5);
      EXPECT_NEAR(b.major, 40, 2);
      EXPECT_NEAR(b.minor, 14, 2);
    } else {
      EXPECT_NEAR(b.major, 40, 2);
      EXPECT_NEAR(b.minor, 40, 2);
    }
    EXPECT_NEAR(b.fill, 1.0, 0.1);
  }
}

TEST(RedBlobs, LinesRingsAndSpecksAreDropped) {
  cv::Mat mask(300, 300, CV_8U, cv::Scalar(0));
  cv::line(mask, {10, 10}, {200, 30}, 255, 2);     // too elongated
  cv::circle(mask, {150, 150}, 40, 255, 3);        // a ring: its fill is far from 1
  cv::rectangle(mask, {250, 250, 2, 1}, 255, -1);  // too small (2 px; the minimum is 3)
  cv::rectangle(mask, {20, 200, 60, 5}, 255, -1);  // elongated bar
  EXPECT_TRUE(FindRedBlobs(mask, {}).empty());
}

TEST(RedBlobs, EightConnectedAcrossADiagonal) {
  cv::Mat mask(20, 20, CV_8U, cv::Scalar(0));
  mask(cv::Rect(2, 2, 3, 3)).setTo(255);
  mask(cv::Rect(5, 5, 3, 3)).setTo(255);  // touches the first only at a corner
  BlobLimits limits;
  limits.min_fill = 0.3;
  const auto blobs = FindRedBlobs(mask, limits);
  ASSERT_EQ(blobs.size(), 1u);
  EXPECT_EQ(blobs[0].area, 18);
}

}  // namespace
}  // namespace pintag::stage

#include "pintag/codec/tag_raster.hpp"

namespace pintag::stage {
namespace {

TEST(RedBlobs, ElementsHaveTheirRingRedMarksOnPaperDoNot) {
  const TagRaster raster = RenderTagRaster(TagKey(77), {120, 4});
  cv::Mat bgr(raster.image.height, raster.image.width, CV_8UC3);
  for (int y = 0; y < bgr.rows; ++y) {
    for (int x = 0; x < bgr.cols; ++x) {
      const Rgb8 c = raster.image.at(x, y);
      bgr.at<cv::Vec3b>(y, x) = {c.b, c.g, c.r};
    }
  }
  const auto elements = FindRedBlobs(RednessMask(bgr, {}), {});
  ASSERT_EQ(elements.size(), 4u);
  for (const RedBlob& b : elements) EXPECT_TRUE(HasRing(bgr, b));

  cv::Mat paper(100, 200, CV_8UC3, cv::Scalar(245, 245, 245));
  cv::circle(paper, {50, 50}, 12, {3, 80, 249}, -1);  // red dot on white
  cv::Mat orange(100, 100, CV_8UC3, cv::Scalar(40, 110, 215));
  orange.copyTo(paper(cv::Rect(100, 0, 100, 100)));
  cv::circle(paper, {150, 50}, 12, {3, 60, 249}, -1);  // red dot on orange
  const auto marks = FindRedBlobs(RednessMask(paper, {}), {});
  for (const RedBlob& b : marks) EXPECT_FALSE(HasRing(paper, b)) << b.centroid;
}

TEST(RedBlobs, RingTableAgreesWithLabApproxOnEveryColour) {
  // HasRing looks colours up in a table built on the assumption that "not ring" (a* >= 10 or
  // L* >= 85) stays true as R grows; over all 2^24 colours the table must say what the rule says.
  long long rings = 0, wrong = 0;
  for (int r = 0; r < 256; ++r) {
    for (int g = 0; g < 256; ++g) {
      for (int b = 0; b < 256; ++b) {
        const bool ring = IsRingColourByLabApprox(r, g, b);
        rings += ring;
        wrong += ring != IsRingColour(r, g, b);
      }
    }
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_GT(rings, 1'000'000);                // greens, greys, blues and darks
  EXPECT_LT(rings, 16'000'000);               // not everything
  EXPECT_TRUE(IsRingColour(40, 160, 60));     // a tag's green
  EXPECT_FALSE(IsRingColour(249, 80, 3));     // its red
  EXPECT_FALSE(IsRingColour(245, 245, 245));  // white paper
}

}  // namespace
}  // namespace pintag::stage
