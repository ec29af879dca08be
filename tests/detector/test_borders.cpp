// Stages 3a and 3e trace dark shapes with TraceBorders, which must list exactly what
// cv::findContours lists (CHAIN_APPROX_SIMPLE): OpenCV is the independent oracle here.

#include <gtest/gtest.h>

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>

#include "candidates/borders.hpp"

namespace pintag::stage {
namespace {

using Borders = std::vector<std::vector<cv::Point>>;

Borders OpenCvOuter(const cv::Mat& binary) {
  Borders all, outer;
  std::vector<cv::Vec4i> hierarchy;
  cv::findContours(binary, all, hierarchy, cv::RETR_CCOMP, cv::CHAIN_APPROX_SIMPLE);
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (hierarchy[i][3] < 0) outer.push_back(all[i]);
  }
  return outer;
}

Borders OpenCvAll(const cv::Mat& binary) {
  Borders all;
  cv::findContours(binary, all, cv::RETR_LIST, cv::CHAIN_APPROX_SIMPLE);
  return all;
}

void ExpectSameAsOpenCv(const cv::Mat& binary, const std::string& what) {
  EXPECT_EQ(TraceBorders(binary, BorderSet::kOuter), OpenCvOuter(binary)) << what;
  EXPECT_EQ(TraceBorders(binary, BorderSet::kAll), OpenCvAll(binary)) << what;
}

TEST(Borders, ListEveryBorderAsOpenCvDoesOnRandomImages) {
  std::mt19937 rng(20261127);
  for (int i = 0; i < 2000; ++i) {
    const int width = 1 + static_cast<int>(rng() % 48);
    const int height = 1 + static_cast<int>(rng() % 48);
    const unsigned per_mille = rng() % 1001;
    // Runs along rows as well as single pixels, so that long borders, holes and shapes nested
    // in holes all occur.
    const unsigned run = 1 + rng() % 6;
    cv::Mat binary(height, width, CV_8U, cv::Scalar(0));
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; x += static_cast<int>(run)) {
        const std::uint8_t v = rng() % 1000 < per_mille ? 255 : 0;
        for (int k = x; k < std::min(width, x + static_cast<int>(run)); ++k) {
          binary.at<std::uint8_t>(y, k) = v;
        }
      }
    }
    ExpectSameAsOpenCv(binary, "image " + std::to_string(i));
    if (HasFailure()) return;
  }
}

TEST(Borders, ListEveryBorderAsOpenCvDoesOnShapes) {
  const auto blank = [](int w, int h) { return cv::Mat(h, w, CV_8U, cv::Scalar(0)); };
  ExpectSameAsOpenCv(blank(9, 7), "nothing");
  ExpectSameAsOpenCv(cv::Mat(7, 9, CV_8U, cv::Scalar(255)), "everything");
  cv::Mat one = blank(5, 5);
  one.at<std::uint8_t>(2, 2) = 1;  // any nonzero value is foreground
  ExpectSameAsOpenCv(one, "a lone pixel");
  ExpectSameAsOpenCv(cv::Mat(1, 12, CV_8U, cv::Scalar(255)), "one row");
  ExpectSameAsOpenCv(cv::Mat(12, 1, CV_8U, cv::Scalar(255)), "one column");
  cv::Mat nested = blank(40, 40);
  cv::rectangle(nested, {2, 2}, {37, 37}, 255, cv::FILLED);    // ground
  cv::rectangle(nested, {8, 8}, {31, 31}, 0, cv::FILLED);      // a quiet zone (hole in the ground)
  cv::rectangle(nested, {12, 12}, {27, 27}, 255, cv::FILLED);  // a tag inside it
  cv::circle(nested, {19, 19}, 3, 0, cv::FILLED);              // and a hole in the tag
  ExpectSameAsOpenCv(nested, "a square in the hole of another");
  EXPECT_EQ(TraceBorders(nested, BorderSet::kOuter).size(), 2U);
  EXPECT_EQ(TraceBorders(nested, BorderSet::kAll).size(), 4U);
  cv::Mat diagonal = blank(6, 6);
  for (int i = 0; i < 6; ++i) diagonal.at<std::uint8_t>(i, i) = 255;  // 8-connected: one shape
  ExpectSameAsOpenCv(diagonal, "a diagonal line");
  EXPECT_EQ(TraceBorders(diagonal, BorderSet::kOuter).size(), 1U);
  cv::Mat checker = blank(9, 8);
  for (int y = 0; y < checker.rows; ++y) {
    for (int x = 0; x < checker.cols; ++x) checker.at<std::uint8_t>(y, x) = (x + y) % 2 ? 255 : 0;
  }
  ExpectSameAsOpenCv(checker, "a checkerboard");
}

TEST(Borders, ReadARegionOfALargerImageInItsOwnCoordinates) {
  cv::Mat image(30, 30, CV_8U, cv::Scalar(0));
  cv::rectangle(image, {5, 5}, {20, 14}, 255, cv::FILLED);
  const cv::Mat region = image(cv::Rect(3, 4, 20, 15));  // not continuous in memory
  ASSERT_FALSE(region.isContinuous());
  ExpectSameAsOpenCv(region, "a region");
  const Borders outer = TraceBorders(region, BorderSet::kOuter);
  ASSERT_EQ(outer.size(), 1U);
  EXPECT_EQ(cv::boundingRect(outer[0]), cv::Rect(2, 1, 16, 10));
}

}  // namespace
}  // namespace pintag::stage
