// A photo without colour holds no readable tag: the detector says so, and only then.

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "colour_content.hpp"
#include "pintag/codec/tag_raster.hpp"
#include "pintag/detector/detector.hpp"

namespace pintag {
namespace {

/// The real tag on a mid-grey page, BGR.
cv::Mat TagOnGrey(TagKey key) {
  const TagRaster tag = RenderTagRaster(key, {.square_px = 120});
  cv::Mat page(300, 400, CV_8UC3, cv::Scalar(128, 128, 128));
  for (int y = 0; y < tag.image.height; ++y) {
    for (int x = 0; x < tag.image.width; ++x) {
      const Rgb8 p = tag.image.at(x, y);
      page.at<cv::Vec3b>(y + 50, x + 100) = {p.b, p.g, p.r};
    }
  }
  return page;
}

cv::Mat Grey(const cv::Mat& bgr) {
  cv::Mat grey;
  cv::Mat out;
  cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
  cv::cvtColor(grey, out, cv::COLOR_GRAY2BGR);
  return out;
}

cv::Mat ThroughJpeg(const cv::Mat& bgr, int quality) {
  std::vector<std::uint8_t> bytes;
  EXPECT_TRUE(cv::imencode(".jpg", bgr, bytes, {cv::IMWRITE_JPEG_QUALITY, quality}));
  return cv::imdecode(bytes, cv::IMREAD_COLOR);
}

TEST(ColourContent, GreyImagesHoldNoneWhateverTheirJpeg) {
  const cv::Mat tag = TagOnGrey(TagKey(11684));
  EXPECT_TRUE(stage::HoldsColour(tag));
  EXPECT_TRUE(stage::HoldsColour(ThroughJpeg(tag, 50)));
  for (const int quality : {30, 75, 95}) {
    EXPECT_FALSE(stage::HoldsColour(ThroughJpeg(Grey(tag), quality))) << quality;
  }
  // A small coloured sticker on a grey page is colour: 12 × 12 pixels give 36 samples.
  cv::Mat sticker = Grey(tag);
  sticker(cv::Rect(10, 10, 12, 12)).setTo(cv::Scalar(40, 60, 200));
  EXPECT_TRUE(stage::HoldsColour(sticker));
  // A few stray coloured pixels are not.
  cv::Mat stray = Grey(tag);
  for (int i = 0; i < 8; ++i) stray.at<cv::Vec3b>(2 * i, 2 * i) = {0, 0, 255};
  EXPECT_FALSE(stage::HoldsColour(stray));
}

TEST(ColourContent, TheDetectorWarnsOnlyWhenNoTagIsReadFromAPhotoWithoutColour) {
  const TagKey key(11684);
  const cv::Mat colour = TagOnGrey(key);
  const DetectResult read = Detector().detect(colour);
  ASSERT_EQ(read.detections.size(), 1U);
  EXPECT_EQ(read.detections[0].key->value(), key.value());
  EXPECT_TRUE(read.warnings.empty());

  const DetectResult grey = Detector().detect(Grey(colour));
  EXPECT_TRUE(grey.detections.empty());
  ASSERT_EQ(grey.warnings.size(), 1U);
  EXPECT_EQ(grey.warnings[0].code, "no_colour");

  // No tag in a colour photo: nothing to warn of.
  cv::Mat page(300, 400, CV_8UC3, cv::Scalar(90, 140, 200));
  const DetectResult empty = Detector().detect(page);
  EXPECT_TRUE(empty.detections.empty());
  EXPECT_TRUE(empty.warnings.empty());
}

}  // namespace
}  // namespace pintag
