// The mosaic re-read (reading/mosaic_reread.hpp): a frame's square cropped with its chroma blocks
// in place, put through each Bayer layout and a bilinear demosaic, and the winner read again there.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <opencv2/imgcodecs.hpp>

#include "reading/decision.hpp"
#include "reading/mosaic_reread.hpp"
#include "reading/residual_correlation.hpp"
#include "synthetic.hpp"

namespace pintag::reading {
namespace {

// Where red sits in each 2 × 2 cell for phases 0 … 3, as the header documents them (RGGB, GRBG,
// GBRG, BGGR), written out here rather than derived the way the code derives it.
const cv::Point kRedSite[4] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};

cv::Mat NoisePicture(int rows, int cols) {
  cv::Mat picture(rows, cols, CV_8UC3);
  cv::RNG rng(17);
  rng.fill(picture, cv::RNG::UNIFORM, 0, 256);
  return picture;
}

TEST(MosaicReread, EveryLayoutGivesAUniformColourBack) {
  const cv::Vec3b colour(40, 120, 210);
  const cv::Mat picture(24, 24, CV_8UC3, cv::Scalar(colour[0], colour[1], colour[2]));
  for (int phase = 0; phase < kMosaicPhases; ++phase) {
    const cv::Mat back = Remosaic(picture, phase);
    ASSERT_EQ(back.size(), picture.size());
    ASSERT_EQ(back.type(), CV_8UC3);
    for (int y = 2; y < 22; ++y) {
      for (int x = 2; x < 22; ++x) {
        const cv::Vec3b& got = back.at<cv::Vec3b>(y, x);
        for (int c = 0; c < 3; ++c) {
          ASSERT_NEAR(got[c], colour[c], 1) << "phase " << phase << " at " << x << "," << y;
        }
      }
    }
  }
}

// Each pixel keeps the colour its filter passed: red where the layout puts red, blue diagonally
// from it, green on the other two; the demosaic only fills in the rest.
TEST(MosaicReread, EachPixelKeepsTheColourItsFilterPasses) {
  const cv::Mat picture = NoisePicture(20, 20);
  for (int phase = 0; phase < kMosaicPhases; ++phase) {
    const cv::Mat back = Remosaic(picture, phase);
    const cv::Point red = kRedSite[phase];
    const cv::Point blue(1 - red.x, 1 - red.y);
    const cv::Point greens[2] = {{1 - red.x, red.y}, {red.x, 1 - red.y}};
    for (int cy = 4; cy < 16; cy += 2) {
      for (int cx = 4; cx < 16; cx += 2) {
        const cv::Point cell(cx, cy);
        EXPECT_EQ(back.at<cv::Vec3b>(cell + red)[2], picture.at<cv::Vec3b>(cell + red)[2]);
        EXPECT_EQ(back.at<cv::Vec3b>(cell + blue)[0], picture.at<cv::Vec3b>(cell + blue)[0]);
        for (const cv::Point g : greens) {
          EXPECT_EQ(back.at<cv::Vec3b>(cell + g)[1], picture.at<cv::Vec3b>(cell + g)[1]);
        }
      }
    }
  }
}

// Where `crop` starts in the frame its square's `corners` were given in; it must be on a 4:2:0
// chroma block (even pixels).
cv::Point2d ExpectStartOnAChromaBlock(const SquareCrop& crop, const Corners& corners) {
  const cv::Point2d origin = corners[0] - crop.corners[0];
  EXPECT_EQ(static_cast<int>(origin.x) % 2, 0);
  EXPECT_EQ(static_cast<int>(origin.y) % 2, 0);
  return origin;
}

TEST(MosaicReread, TheCropStartsOnAChromaBlockAndHoldsTheSquare) {
  const cv::Mat frame = NoisePicture(200, 300);
  const Corners corners = {cv::Point2d(101.3, 77.6), cv::Point2d(131.2, 80.1),
                           cv::Point2d(128.9, 109.4), cv::Point2d(99.7, 106.8)};
  const SquareCrop crop = CropAroundCorners(frame, corners);
  ASSERT_FALSE(crop.bgr.empty());
  const cv::Point2d origin = ExpectStartOnAChromaBlock(crop, corners);
  EXPECT_LE(origin.x, 99.7 - kMosaicCropMarginPx);
  EXPECT_LE(origin.y, 77.6 - kMosaicCropMarginPx);
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_EQ(crop.corners[k], corners[k] - origin);
    // The crop keeps the margin on every side.
    EXPECT_GE(crop.corners[k].x, kMosaicCropMarginPx);
    EXPECT_GE(crop.corners[k].y, kMosaicCropMarginPx);
    EXPECT_LE(crop.corners[k].x, crop.bgr.cols - kMosaicCropMarginPx);
    EXPECT_LE(crop.corners[k].y, crop.bgr.rows - kMosaicCropMarginPx);
  }
  const cv::Point at(110, 90);
  EXPECT_EQ(crop.bgr.at<cv::Vec3b>(at - cv::Point(origin)), frame.at<cv::Vec3b>(at));

  // Near the frame's top-left corner the crop starts at the frame's.
  const Corners near_origin = {cv::Point2d(3.5, 5.5), cv::Point2d(30.5, 5.5),
                               cv::Point2d(30.5, 32.5), cv::Point2d(3.5, 32.5)};
  EXPECT_EQ(CropAroundCorners(frame, near_origin).corners[0], near_origin[0]);

  // Near the bottom-right one, in a frame of odd size, it ends at the frame's and still starts on
  // even pixels.
  const cv::Mat odd = NoisePicture(201, 301);
  const Corners near_end = {cv::Point2d(271.5, 171.5), cv::Point2d(296.5, 171.5),
                            cv::Point2d(296.5, 196.5), cv::Point2d(271.5, 196.5)};
  const SquareCrop at_end = CropAroundCorners(odd, near_end);
  ASSERT_FALSE(at_end.bgr.empty());
  const cv::Point2d end_origin = ExpectStartOnAChromaBlock(at_end, near_end);
  EXPECT_EQ(end_origin.x + at_end.bgr.cols, odd.cols);
  EXPECT_EQ(end_origin.y + at_end.bgr.rows, odd.rows);

  // A corner that is not a number gives no crop (and so no re-read).
  Corners broken = corners;
  broken[2].y = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(CropAroundCorners(frame, broken).bgr.empty());
}

// A small, blurred tag saved as a phone saves it: its right winner survives a mosaic of our own
// in at least one layout, and no layout accepts a codeword it does not hold.
TEST(MosaicReread, ARightWinnerIsAcceptedAgainAndAnotherCodewordIsNot) {
  for (const int key : {4660, 27851}) {
    testing::SyntheticOptions o;
    o.seed = static_cast<std::uint64_t>(key);
    o.blur_sigma = 0.7;
    o.noise_sigma = 1.5;
    const auto scene =
        testing::MakeScene({{.key = key, .square_px = 36, .tilt_deg = 20, .roll_deg = 15}}, o);
    std::vector<std::uint8_t> bytes;
    cv::imencode(".jpg", scene.bgr, bytes, {cv::IMWRITE_JPEG_QUALITY, 92});
    const cv::Mat jpeg = cv::imdecode(bytes, cv::IMREAD_COLOR);
    const auto& truth = scene.truth[0].corners;
    const ModelReading first =
        ReadThroughModel(jpeg, ChromaUpsampling::kBoth, {truth[0], truth[1], truth[2], truth[3]});
    ASSERT_EQ(RefuseCodeword(first), "") << key;
    ASSERT_EQ(first.decision.winner->value(), key);
    const SquareCrop crop = CropAroundCorners(jpeg, first.fit.corners);
    int accepted = 0;
    for (int phase = 0; phase < kMosaicPhases; ++phase) {
      const MosaicReread again =
          ReadThroughMosaic(crop, ChromaUpsampling::kBoth, *first.decision.winner, phase);
      accepted += again.accepted_again ? 1 : 0;
      EXPECT_GT(again.fit_ms, 0);
      const TagKey other(static_cast<std::uint16_t>(key ^ 1));
      EXPECT_FALSE(ReadThroughMosaic(crop, ChromaUpsampling::kBoth, other, phase).accepted_again)
          << key << " phase " << phase;
    }
    EXPECT_GE(accepted, 1) << key;
  }
}

TEST(MosaicReread, OnlyWinnersUnderTheLeadAreChecked) {
  ModelReading reading;
  reading.fit.luma_noise = kLumaNoiseFloor;  // the lead counts in full
  const double inflation = VarianceInflation(reading.fit.chroma_correlation);
  reading.decision.lead = 0.99 * kMosaicCheckMaxIndependentLead * inflation;
  EXPECT_TRUE(NeedsMosaicCheck(reading));
  reading.decision.lead = 1.01 * kMosaicCheckMaxIndependentLead * inflation;
  EXPECT_FALSE(NeedsMosaicCheck(reading));
  // A lead counted below the luminance noise floor shrinks, and is checked again.
  reading.fit.luma_noise = kLumaNoiseFloor / 2;
  EXPECT_TRUE(NeedsMosaicCheck(reading));
  reading.decision.lead = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(NeedsMosaicCheck(reading));
}

}  // namespace
}  // namespace pintag::reading
