// Stage 5b's observations: the colour a tag's model is fitted to is close to what the JPEG stores,
// not the decoder's upsampled interpolation of it.

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <vector>

#include "pintag/detector/image_io.hpp"
#include "reading/tag_samples.hpp"

namespace pintag::reading {
namespace {

// A frame whose colour changes from one 2 × 2 block to the next, as a tag's cells do at 24 px:
// random Cb and Cr per block (within ±45 levels of grey, so that no channel clips) on a luma ramp.
cv::Mat BlockColourFrame(int width, int height, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> chroma(-45, 45);
  cv::Mat bgr(height, width, CV_8UC3);
  for (int by = 0; by < height / 2; ++by) {
    for (int bx = 0; bx < width / 2; ++bx) {
      const double cb = chroma(rng), cr = chroma(rng);
      for (int dy = 0; dy < 2; ++dy) {
        for (int dx = 0; dx < 2; ++dx) {
          const int x = 2 * bx + dx, y = 2 * by + dy;
          const double luma = 100 + 40.0 * x / width;  // BT.601 full range, as JPEG
          cv::Vec3b& p = bgr.at<cv::Vec3b>(y, x);
          p[2] = cv::saturate_cast<std::uint8_t>(luma + 1.402 * cr);
          p[1] = cv::saturate_cast<std::uint8_t>(luma - 0.344136 * cb - 0.714136 * cr);
          p[0] = cv::saturate_cast<std::uint8_t>(luma + 1.772 * cb);
        }
      }
    }
  }
  return bgr;
}

struct ChromaErrors {
  double undone = 0;    // mean |sample − stored| of SampleTag's samples
  double averaged = 0;  // the same for the plain 2 × 2 mean of the decoded pixels
  int samples = 0;
};

ChromaErrors CompareWithStoredPlanes(int quality, unsigned seed) {
  const cv::Mat frame = BlockColourFrame(160, 160, seed);
  std::vector<std::uint8_t> jpeg;
  EXPECT_TRUE(cv::imencode(".jpg", frame, jpeg, {cv::IMWRITE_JPEG_QUALITY, quality}));
  const LoadResult decoded = LoadImageBytes(jpeg);
  const JpegPlanesResult stored = LoadJpegPlanes(jpeg);
  EXPECT_TRUE(decoded.image && stored.planes);
  ChromaErrors e;
  if (!decoded.image || !stored.planes) return e;
  EXPECT_EQ(stored.planes->cb.size(), cv::Size(80, 80));  // OpenCV writes 4:2:0
  const cv::Mat& bgr = decoded.image->bgr;
  // The unit square over the middle of the frame: its samples reach 0.06 of a side beyond it.
  const cv::Matx33d square_to_image(100, 0, 30, 0, 100, 30, 0, 0, 1);
  const TagSamples samples = SampleTag(bgr, square_to_image);
  for (const ChromaSample& s : samples.chroma) {
    const double stored_cb = (stored.planes->cb.at<std::uint8_t>(s.y / 2, s.x / 2) - 128) / 255.0;
    const double stored_cr = (stored.planes->cr.at<std::uint8_t>(s.y / 2, s.x / 2) - 128) / 255.0;
    double mean_cb = 0, mean_cr = 0;
    for (int dy = 0; dy < 2; ++dy) {
      for (int dx = 0; dx < 2; ++dx) {
        const cv::Vec3b p = bgr.at<cv::Vec3b>(s.y + dy, s.x + dx);
        const double luma = (0.299 * p[2] + 0.587 * p[1] + 0.114 * p[0]) / 255.0;
        mean_cb += (p[0] / 255.0 - luma) / 1.772 / 4;
        mean_cr += (p[2] / 255.0 - luma) / 1.402 / 4;
      }
    }
    e.undone += std::abs(s.cb - stored_cb) + std::abs(s.cr - stored_cr);
    e.averaged += std::abs(mean_cb - stored_cb) + std::abs(mean_cr - stored_cr);
    ++e.samples;
  }
  e.undone /= 2 * e.samples;
  e.averaged /= 2 * e.samples;
  return e;
}

// The decoder's triangle upsampling blurs each block's colour with its neighbours'; undone, the
// samples are the stored ones up to the decoded pixels' rounding (and the box's edges, where the
// neighbours outside are not seen).
TEST(TagSamples, ColourIsTheJpegsStoredChromaNotItsUpsampling) {
  for (const int quality : {75, 95}) {
    for (const unsigned seed : {1U, 2U}) {
      const ChromaErrors e = CompareWithStoredPlanes(quality, seed);
      ASSERT_GT(e.samples, 1000);
      EXPECT_LT(e.undone, 0.1 * e.averaged) << "quality " << quality << " seed " << seed;
      EXPECT_LT(e.undone, 1.0 / 255) << "quality " << quality << " seed " << seed;
    }
  }
}

TEST(TagSamples, UndoingTheUpsamplingKeepsFlatColour) {
  cv::Mat grid(7, 9, CV_64F, cv::Scalar(0.125));
  UndoChromaUpsampling(&grid);
  double low = 0, high = 0;
  cv::minMaxLoc(grid, &low, &high);
  EXPECT_NEAR(low, 0.125, 1e-12);
  EXPECT_NEAR(high, 0.125, 1e-12);
  cv::Mat small(2, 5, CV_64F, cv::Scalar(0.5));
  small.at<double>(0, 0) = -0.5;
  const cv::Mat before = small.clone();
  UndoChromaUpsampling(&small);  // under 3 × 3: left as it is
  EXPECT_EQ(cv::norm(small, before, cv::NORM_INF), 0);
}

}  // namespace
}  // namespace pintag::reading
