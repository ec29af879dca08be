// Stage 5b: cells read through a blur model, where direct samples of a small blurred tag mix.

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <optional>

#include "blur_model.hpp"
#include "homography.hpp"
#include "orientation.hpp"
#include "payload.hpp"
#include "pintag/codec/geometry.hpp"
#include "synthetic.hpp"

namespace pintag::stage {
namespace {

std::optional<TagKey> Decode(const CellSamples& samples) {
  const OrientationResult orientation = ReadOrientation(samples, BitThresholds{});
  if (!orientation.ok) return std::nullopt;
  const PayloadResult payload = DecodePayload(orientation.reading);
  if (!payload.key) return std::nullopt;
  return payload.key;
}

cv::Matx33d TrueHomography(const testing::SyntheticTruth& truth) {
  Quad quad;
  for (int i = 0; i < 4; ++i) quad[i] = truth.corners[i];
  return HomographyFromQuad(quad);
}

TEST(BlurModel, RegionsAreTheFormatsCells) {
  int checked = 0;
  for (int iy = -20; iy <= 420; ++iy) {
    for (int ix = -20; ix <= 420; ++ix) {
      // Offsets keep the points off the cell boundaries, where the two may round differently.
      const double x = (ix + 0.37) / 400, y = (iy + 0.61) / 400;
      const geometry::CellAt cell = geometry::LocateCell(x, y);
      int expected = 0;
      switch (cell.region) {
        case geometry::Region::kOutside:
          expected = 0;
          break;
        case geometry::Region::kBlack:
          expected = 1;
          break;
        case geometry::Region::kRed:
          expected = 2 + 12 * cell.element + cell.index;
          break;
        case geometry::Region::kGreen:
          expected = 2 + 12 * cell.element + 4 + cell.index;
          break;
      }
      ASSERT_EQ(ModelRegionAt(x, y), expected) << x << ", " << y;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 441 * 441);
}

// One 30 px tag, blurred (σ px, round) and noised, at a tilt and roll.
testing::SyntheticScene SmallBlurredTag(int key, double tilt_deg, double roll_deg, double sigma,
                                        double noise, std::uint64_t seed) {
  testing::SyntheticOptions o;
  o.seed = seed;
  o.blur_sigma = sigma;
  o.noise_sigma = noise;
  return testing::MakeScene(
      {{.key = key, .square_px = 30, .tilt_deg = tilt_deg, .roll_deg = roll_deg}}, o);
}

// The blur fit of such a tag on its true homography; the seed varies with key and roll.
BlurFit FitSmallBlurredTag(int key, double tilt_deg, double roll_deg, double sigma, double noise,
                           std::uint64_t seed_per_key) {
  const auto scene = SmallBlurredTag(
      key, tilt_deg, roll_deg, sigma, noise,
      static_cast<std::uint64_t>(key) * seed_per_key + static_cast<std::uint64_t>(roll_deg));
  return FitCellsThroughBlur(scene.bgr, TrueHomography(scene.truth[0]));
}

TEST(BlurModel, ReadsSmallBlurredTagsThatDirectSamplesCannot) {
  int direct = 0, fitted = 0, cases = 0;
  for (const int key : {0, 1, 4660, 13107, 21845, 32767}) {
    for (const double roll : {0.0, 33.0}) {
      const auto scene =
          SmallBlurredTag(key, 20, roll, 1.6, 2,
                          static_cast<std::uint64_t>(key) * 7 + static_cast<std::uint64_t>(roll));
      const cv::Matx33d h = TrueHomography(scene.truth[0]);
      ++cases;
      const std::optional<TagKey> read = Decode(SampleCells(scene.bgr, h));
      if (read) {
        EXPECT_EQ(read->value(), key);
        ++direct;
      }
      const BlurFit fit = FitCellsThroughBlur(scene.bgr, h);
      ASSERT_TRUE(fit.ok) << key;
      const std::optional<TagKey> modelled = Decode(fit.cells);
      ASSERT_TRUE(modelled.has_value()) << "key " << key << " roll " << roll;
      EXPECT_EQ(modelled->value(), key);
      ++fitted;
      // The blur found explains the one applied (σ 1.6 px, round) within the search's steps.
      EXPECT_NEAR(fit.sigma_major_px, 1.6, 0.6) << key;
      EXPECT_NEAR(fit.sigma_minor_px, 1.6, 0.6) << key;
    }
  }
  EXPECT_EQ(fitted, cases);
  EXPECT_LE(2 * direct, cases) << "these scenes should defeat direct sampling mostly";
}

// The two-colours-per-class reading (the detector's last resort) on small blurred tags: it must
// decode a good share and never give another key.
TEST(BlurModel, BitsModelNeverGivesAnotherKey) {
  int decoded = 0, cases = 0;
  for (const int key : {1, 4660, 13107, 21845, 30000}) {
    for (const double roll : {10.0, 55.0}) {
      const BlurFit fit = FitSmallBlurredTag(key, 30, roll, 1.9, 3, 3);
      ASSERT_TRUE(fit.ok);
      ++cases;
      const ModelReading bits = ReadBitsThroughBlur(fit, SettleOrientations(fit));
      if (!bits.ok) continue;
      const PayloadResult payload = DecodePayload(bits.reading);
      if (!payload.key) continue;
      EXPECT_EQ(payload.key->value(), key) << "roll " << roll;
      ++decoded;
    }
  }
  EXPECT_GE(2 * decoded, cases - 2);
}

// The nearest-codeword decode (after the bit readers) on tags too blurred for them: whatever it
// accepts must be the right key, and it must accept most.
TEST(BlurModel, NearestCodewordIsTheRightKeyOrNone) {
  int decoded = 0, cases = 0;
  for (const int key : {0, 2, 9999, 17000, 24680, 32767}) {
    for (const double roll : {5.0, 40.0}) {
      const BlurFit fit = FitSmallBlurredTag(key, 35, roll, 2.2, 4, 5);
      ASSERT_TRUE(fit.ok);
      ++cases;
      const CodewordReading nearest = NearestCodewordThroughBlur(fit, SettleOrientations(fit));
      if (!nearest.key) continue;
      EXPECT_EQ(nearest.key->value(), key) << "roll " << roll;
      EXPECT_GE(nearest.lead, 25);
      // No worse than the free reading, or by at most a tenth of a lead of at least 100.
      EXPECT_LE(nearest.excess, nearest.lead >= 100 ? 0.1 * nearest.lead : 0.0);
      ++decoded;
    }
  }
  EXPECT_GE(2 * decoded, cases);
}

TEST(BlurModel, ABlackSquareWithoutElementsGivesNoKey) {
  cv::Mat bgr(120, 120, CV_8UC3, cv::Scalar(235, 235, 235));
  cv::rectangle(bgr, {40, 40}, {79, 79}, cv::Scalar(25, 25, 25), cv::FILLED);
  cv::GaussianBlur(bgr, bgr, {}, 1.2);
  const Quad quad = {cv::Point2d(39.5, 39.5), {79.5, 39.5}, {79.5, 79.5}, {39.5, 79.5}};
  const BlurFit fit = FitCellsThroughBlur(bgr, HomographyFromQuad(quad));
  ASSERT_TRUE(fit.ok);
  EXPECT_FALSE(Decode(fit.cells).has_value());
  const ModelReading bits = ReadBitsThroughBlur(fit, SettleOrientations(fit));
  EXPECT_FALSE(bits.ok && DecodePayload(bits.reading).key.has_value());
  EXPECT_FALSE(NearestCodewordThroughBlur(fit, SettleOrientations(fit)).key.has_value());
}

// Squares that are not tags (random colourful blotches in a black square with a white margin)
// must give no codeword.
TEST(BlurModel, ColourfulNonTagsGiveNoCodeword) {
  cv::RNG rng(7);
  for (int trial = 0; trial < 12; ++trial) {
    cv::Mat bgr(120, 120, CV_8UC3, cv::Scalar(235, 235, 235));
    cv::rectangle(bgr, {40, 40}, {79, 79}, cv::Scalar(25, 25, 25), cv::FILLED);
    for (int blob = 0; blob < 6; ++blob) {
      const cv::Point centre(rng.uniform(44, 76), rng.uniform(44, 76));
      const cv::Scalar colour(rng.uniform(0, 256), rng.uniform(0, 256), rng.uniform(0, 256));
      cv::circle(bgr, centre, rng.uniform(2, 7), colour, cv::FILLED);
    }
    cv::GaussianBlur(bgr, bgr, {}, 1.5);
    const Quad quad = {cv::Point2d(39.5, 39.5), {79.5, 39.5}, {79.5, 79.5}, {39.5, 79.5}};
    const BlurFit fit = FitCellsThroughBlur(bgr, HomographyFromQuad(quad));
    ASSERT_TRUE(fit.ok);
    EXPECT_FALSE(NearestCodewordThroughBlur(fit, SettleOrientations(fit)).key.has_value())
        << "trial " << trial;
  }
}

TEST(BlurModel, LargeTagsAndTagsOffTheImageAreLeftToDirectSampling) {
  const cv::Mat bgr(400, 400, CV_8UC3, cv::Scalar(200, 200, 200));
  const Quad large = {cv::Point2d(50, 50), {250, 50}, {250, 250}, {50, 250}};
  EXPECT_FALSE(FitCellsThroughBlur(bgr, HomographyFromQuad(large)).ok);
  const Quad outside = {cv::Point2d(-500, -500), {-460, -500}, {-460, -460}, {-500, -460}};
  EXPECT_FALSE(FitCellsThroughBlur(bgr, HomographyFromQuad(outside)).ok);
}

}  // namespace
}  // namespace pintag::stage
