// Stage 5b's observations: the colour a tag's model is fitted to is close to what the JPEG stores,
// not the decoder's upsampled interpolation of it, whatever the file's chroma subsampling; and
// colour that was never subsampled is left as it is.

#include <gtest/gtest.h>
#include <turbojpeg.h>

#include <cmath>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <string>
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

std::vector<std::uint8_t> EncodeJpeg(const cv::Mat& bgr, int quality, int subsampling) {
  const std::unique_ptr<void, int (*)(tjhandle)> tj(tjInitCompress(), tjDestroy);
  unsigned char* jpeg = nullptr;
  unsigned long size = 0;  // NOLINT(google-runtime-int): TurboJPEG's type
  const int status = tjCompress2(tj.get(), bgr.data, bgr.cols, static_cast<int>(bgr.step), bgr.rows,
                                 TJPF_BGR, &jpeg, &size, subsampling, quality, 0);
  const std::unique_ptr<unsigned char, void (*)(unsigned char*)> owned(jpeg, tjFree);
  EXPECT_EQ(status, 0) << tjGetErrorStr2(tj.get());
  return status == 0 ? std::vector<std::uint8_t>(jpeg, jpeg + size) : std::vector<std::uint8_t>{};
}

struct ChromaErrors {
  double sampled = 0;   // mean |sample − stored| of SampleTag's samples
  double averaged = 0;  // the same for the plain 2 × 2 mean of the decoded pixels
  int samples = 0;
};

// SampleTag's colour over the middle of a JPEG of `subsampling`, against the mean of the stored
// chroma samples each 2 × 2 block covers. `upsampling` overrides what the loader reported.
ChromaErrors CompareWithStoredPlanes(int quality, int subsampling, unsigned seed,
                                     const ChromaUpsampling* upsampling = nullptr) {
  const std::vector<std::uint8_t> jpeg =
      EncodeJpeg(BlockColourFrame(160, 160, seed), quality, subsampling);
  const LoadResult decoded = LoadImageBytes(jpeg);
  const JpegPlanesResult stored = LoadJpegPlanes(jpeg);
  EXPECT_TRUE(decoded.image && stored.planes);
  ChromaErrors e;
  if (!decoded.image || !stored.planes) return e;
  const cv::Mat& bgr = decoded.image->bgr;
  const cv::Mat& cb_plane = stored.planes->cb;
  const cv::Mat& cr_plane = stored.planes->cr;
  // How many pixels one stored sample spans, across and down.
  const int step_x = bgr.cols / cb_plane.cols, step_y = bgr.rows / cb_plane.rows;
  // The unit square over the middle of the frame: its samples reach 0.06 of a side beyond it.
  const cv::Matx33d square_to_image(100, 0, 30, 0, 100, 30, 0, 0, 1);
  const TagSamples samples = SampleTag(
      bgr, upsampling != nullptr ? *upsampling : decoded.image->chroma_upsampling, square_to_image);
  for (const ChromaSample& s : samples.chroma) {
    double stored_cb = 0, stored_cr = 0, mean_cb = 0, mean_cr = 0;
    for (int dy = 0; dy < 2; ++dy) {
      for (int dx = 0; dx < 2; ++dx) {
        const int x = s.x + dx, y = s.y + dy;
        stored_cb += (cb_plane.at<std::uint8_t>(y / step_y, x / step_x) - 128) / 255.0 / 4;
        stored_cr += (cr_plane.at<std::uint8_t>(y / step_y, x / step_x) - 128) / 255.0 / 4;
        const cv::Vec3b p = bgr.at<cv::Vec3b>(y, x);
        const double luma = (0.299 * p[2] + 0.587 * p[1] + 0.114 * p[0]) / 255.0;
        mean_cb += (p[0] / 255.0 - luma) / 1.772 / 4;
        mean_cr += (p[2] / 255.0 - luma) / 1.402 / 4;
      }
    }
    e.sampled += std::abs(s.cb - stored_cb) + std::abs(s.cr - stored_cr);
    e.averaged += std::abs(mean_cb - stored_cb) + std::abs(mean_cr - stored_cr);
    ++e.samples;
  }
  e.sampled /= 2 * e.samples;
  e.averaged /= 2 * e.samples;
  return e;
}

std::string Name(int subsampling) {
  switch (subsampling) {
    case TJSAMP_420:
      return "4:2:0";
    case TJSAMP_422:
      return "4:2:2";
    case TJSAMP_440:
      return "4:4:0";
    case TJSAMP_444:
      return "4:4:4";
  }
  return "other";
}

// The decoder's triangle upsampling blurs each block's colour with its neighbours' (both ways for
// 4:2:0, along one axis for 4:2:2 and 4:4:0); undone, the samples are the stored ones up to the
// decoded pixels' rounding (and the box's edges, where the neighbours outside are not seen).
TEST(TagSamples, ColourIsTheJpegsStoredChromaNotItsUpsampling) {
  for (const int subsampling : {TJSAMP_420, TJSAMP_422, TJSAMP_440}) {
    for (const int quality : {75, 95}) {
      for (const unsigned seed : {1U, 2U}) {
        const ChromaErrors e = CompareWithStoredPlanes(quality, subsampling, seed);
        const std::string what = Name(subsampling) + " quality " + std::to_string(quality) +
                                 " seed " + std::to_string(seed);
        ASSERT_GT(e.samples, 1000) << what;
        EXPECT_LT(e.sampled, 0.1 * e.averaged) << what;
        EXPECT_LT(e.sampled, 1.0 / 255) << what;
      }
    }
  }
}

// Colour stored at full resolution was never interpolated: it is sampled as it is, and "undoing"
// a 4:2:0 upsampling on it would sharpen it away from what the file holds.
TEST(TagSamples, FullResolutionColourIsLeftAsItIs) {
  for (const unsigned seed : {1U, 2U}) {
    const ChromaErrors as_loaded = CompareWithStoredPlanes(90, TJSAMP_444, seed);
    ASSERT_GT(as_loaded.samples, 1000);
    EXPECT_LT(as_loaded.sampled, 1.0 / 255) << "seed " << seed;
    EXPECT_NEAR(as_loaded.sampled, as_loaded.averaged, 1e-9) << "seed " << seed;
    const ChromaUpsampling wrong = ChromaUpsampling::kBoth;
    const ChromaErrors undone = CompareWithStoredPlanes(90, TJSAMP_444, seed, &wrong);
    EXPECT_GT(undone.sampled, 3 * as_loaded.sampled) << "seed " << seed;
  }
}

// A lossy WebP keeps colour at 4:2:0 too, and libwebp's decoder interpolates it as libjpeg's does:
// with the loader's word for it, the samples come closer to each block's colour in the source than
// the plain mean of the decoded pixels does. (WebP's stored planes are not at hand, so the source
// stands in for them, and the encoder's losses stay in both errors.)
TEST(TagSamples, LossyWebpColourIsUndoneToo) {
  for (const unsigned seed : {1U, 2U}) {
    const cv::Mat frame = BlockColourFrame(160, 160, seed);
    std::vector<std::uint8_t> webp;
    ASSERT_TRUE(cv::imencode(".webp", frame, webp, {cv::IMWRITE_WEBP_QUALITY, 95}));
    const LoadResult decoded = LoadImageBytes(webp);
    ASSERT_TRUE(decoded.image) << decoded.error;
    ASSERT_EQ(decoded.image->chroma_upsampling, ChromaUpsampling::kBoth);
    const cv::Matx33d square_to_image(100, 0, 30, 0, 100, 30, 0, 0, 1);
    const TagSamples undone =
        SampleTag(decoded.image->bgr, ChromaUpsampling::kBoth, square_to_image);
    const TagSamples averaged =
        SampleTag(decoded.image->bgr, ChromaUpsampling::kNone, square_to_image);
    ASSERT_EQ(undone.chroma.size(), averaged.chroma.size());
    ASSERT_GT(undone.chroma.size(), 1000U);
    double undone_error = 0, averaged_error = 0;
    for (std::size_t i = 0; i < undone.chroma.size(); ++i) {
      const ChromaSample& u = undone.chroma[i];
      const cv::Vec3b& p = frame.at<cv::Vec3b>(u.y, u.x);  // the block's one colour
      const double luma = (0.299 * p[2] + 0.587 * p[1] + 0.114 * p[0]) / 255.0;
      const double cb = (p[0] / 255.0 - luma) / 1.772, cr = (p[2] / 255.0 - luma) / 1.402;
      undone_error += std::abs(u.cb - cb) + std::abs(u.cr - cr);
      averaged_error += std::abs(averaged.chroma[i].cb - cb) + std::abs(averaged.chroma[i].cr - cr);
    }
    EXPECT_LT(undone_error, 0.5 * averaged_error) << "seed " << seed;
  }
}

TEST(TagSamples, UndoingTheUpsamplingKeepsFlatColour) {
  for (const ChromaUpsampling upsampling :
       {ChromaUpsampling::kBoth, ChromaUpsampling::kAcross, ChromaUpsampling::kDown}) {
    cv::Mat grid(7, 9, CV_64F, cv::Scalar(0.125));
    UndoChromaUpsampling(&grid, upsampling);
    double low = 0, high = 0;
    cv::minMaxLoc(grid, &low, &high);
    EXPECT_NEAR(low, 0.125, 1e-12);
    EXPECT_NEAR(high, 0.125, 1e-12);
  }
  cv::Mat small(2, 5, CV_64F, cv::Scalar(0.5));
  small.at<double>(0, 0) = -0.5;
  const cv::Mat before = small.clone();
  UndoChromaUpsampling(&small, ChromaUpsampling::kBoth);  // under 3 down: left as it is
  EXPECT_EQ(cv::norm(small, before, cv::NORM_INF), 0);
  UndoChromaUpsampling(&small, ChromaUpsampling::kNone);
  EXPECT_EQ(cv::norm(small, before, cv::NORM_INF), 0);
  UndoChromaUpsampling(&small, ChromaUpsampling::kAcross);  // 5 across: undone
  EXPECT_GT(cv::norm(small, before, cv::NORM_INF), 0.1);
}

}  // namespace
}  // namespace pintag::reading
