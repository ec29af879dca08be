// The model reader (reading/): a tag's luminance and its 4:2:0 chroma explained by its regions
// under a searched blur, its corners refined, its codeword decided over the whole code, and the
// rule that accepts it.

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "homography.hpp"
#include "pintag/codec/geometry.hpp"
#include "reading/decision.hpp"
#include "reading/model_reader.hpp"
#include "reading/model_regions.hpp"
#include "reading/read_tag.hpp"
#include "synthetic.hpp"

namespace pintag::reading {
namespace {

Corners TrueCorners(const testing::SyntheticTruth& truth) {
  return {truth.corners[0], truth.corners[1], truth.corners[2], truth.corners[3]};
}

cv::Mat Jpeg420(const cv::Mat& bgr, int quality) {
  std::vector<std::uint8_t> bytes;
  // OpenCV 4.6 leaves the sampling to libjpeg, whose default is 4:2:0.
  cv::imencode(".jpg", bgr, bytes, {cv::IMWRITE_JPEG_QUALITY, quality});
  return cv::imdecode(bytes, cv::IMREAD_COLOR);
}

// One tag of `side` px, blurred (σ px, round) and noised, at a tilt and roll.
testing::SyntheticScene Tag(int key, double side, double tilt_deg, double roll_deg, double sigma,
                            double noise, std::uint64_t seed) {
  testing::SyntheticOptions o;
  o.seed = seed;
  o.blur_sigma = sigma;
  o.noise_sigma = noise;
  return testing::MakeScene(
      {{.key = key, .square_px = side, .tilt_deg = tilt_deg, .roll_deg = roll_deg}}, o);
}

// The model's reading of a clean 40 px tag on its true corners, accepted as it is read: the
// decision tests set its statistics by hand to reach each side of a rule. Its luminance noise is
// raised to kLumaNoiseFloor where it is under it, so that a lead set by hand counts in full.
ModelReading ReadingToJudge() {
  const auto scene = Tag(4242, 40, 20, 11, 0.8, 1, 3);
  ModelReading reading =
      ReadThroughModel(scene.bgr, ChromaUpsampling::kNone, TrueCorners(scene.truth[0]));
  reading.fit.luma_noise = std::max(reading.fit.luma_noise, kLumaNoiseFloor);
  return reading;
}

constexpr const char* kRefusedForExcess =
    "codeword explains the pixels worse than its cells read freely";

// `corners` squeezed towards their centre line across one pair of sides (C0 C1 against C3 C2), to
// `extent_px` across: a square made narrow one way by hand.
Corners SqueezedAcross(const Corners& corners, double extent_px) {
  const cv::Point2d mid01 = (corners[0] + corners[1]) / 2, mid32 = (corners[3] + corners[2]) / 2;
  const double across = cv::norm(mid32 - mid01);
  const double k = extent_px / across;
  const cv::Point2d centre = (mid01 + mid32) / 2;
  const cv::Point2d unit = (mid32 - mid01) / across;
  Corners squeezed = corners;
  for (cv::Point2d& p : squeezed) p -= (1 - k) * unit * (p - centre).dot(unit);
  return squeezed;
}

TEST(ModelReader, RegionsAreTheFormatsCells) {
  int checked = 0;
  for (int iy = -20; iy <= 420; ++iy) {
    for (int ix = -20; ix <= 420; ++ix) {
      // Offsets keep the points off the cell boundaries, where the two may round differently.
      const double x = (ix + 0.37) / 400, y = (iy + 0.61) / 400;
      const geometry::CellAt cell = geometry::LocateCell(x, y);
      int expected = kQuietRegion;
      switch (cell.region) {
        case geometry::Region::kOutside:
          break;
        case geometry::Region::kBlack:
          expected = kBlackRegion;
          break;
        case geometry::Region::kRed:
          expected = RedRegion(cell.element, cell.index);
          break;
        case geometry::Region::kGreen:
          expected = GreenRegion(cell.element, cell.index);
          break;
      }
      ASSERT_EQ(ModelRegionAt(x, y), expected) << x << ", " << y;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 441 * 441);
}

// The codeword search finds a codeword's neighbours as key offsets, which holds only while the
// codec's code is affine: checked on every key against its bits' codewords, and the offsets'
// neighbourhoods against a scan of the whole codebook.
TEST(ModelReader, NeighbourOffsetsGiveEveryCodewordWithinSevenCells) {
  const std::vector<std::uint64_t>& book = Codebook();
  ASSERT_EQ(book.size(), static_cast<std::size_t>(kKeyCount));
  for (int k = 0; k < kKeyCount; ++k) {
    std::uint64_t sum = book[0];
    for (int bit = 0; (1 << bit) < kKeyCount; ++bit) {
      if ((k >> bit) & 1) sum ^= book[std::size_t{1} << bit] ^ book[0];
    }
    ASSERT_EQ(sum, book[static_cast<std::size_t>(k)]) << "key " << k;
  }
  const std::vector<int>& offsets = NeighbourKeyOffsets();
  EXPECT_GT(offsets.size(), 16U);
  for (const int centre : {0, 1, 4242, 12345, 29579, kKeyCount - 1}) {
    std::vector<int> scanned;
    for (int k = 0; k < kKeyCount; ++k) {
      const int cells =
          std::popcount(book[static_cast<std::size_t>(k)] ^ book[static_cast<std::size_t>(centre)]);
      if (k != centre && cells <= kNeighbourCells) scanned.push_back(k);
    }
    std::vector<int> offset;
    offset.reserve(offsets.size());
    for (const int d : offsets) offset.push_back(centre ^ d);
    std::sort(offset.begin(), offset.end());
    EXPECT_EQ(offset, scanned) << "centre " << centre;
  }
}

TEST(ModelReader, ExplainsASharpCleanTagClosely) {
  const auto scene = Tag(12345, 40, 30, 17, 0, 0, 1);
  const ModelReading r =
      ReadThroughModel(scene.bgr, ChromaUpsampling::kNone, TrueCorners(scene.truth[0]));
  ASSERT_TRUE(r.fit.ok) << r.error;
  // What is left is the sub-sampled coverage and the renderer's own anti-aliasing: far below the
  // luminance steps between a tag's colours (0.1 and more).
  EXPECT_LT(r.fit.luma_noise, 0.02);
  EXPECT_LT(r.fit.luma_blur.major, 0.7);
  ASSERT_TRUE(r.decision.winner);
  EXPECT_EQ(r.decision.winner->value(), 12345);
  EXPECT_EQ(RefuseCodeword(r), "");
  EXPECT_GT(r.decision.lead, 1000);
}

// Small blurred tags, which direct samples mostly cannot read: every one is read right, and the
// blur found is the one applied (σ 1.6 px, round) within the search's steps.
TEST(ModelReader, ReadsSmallBlurredTags) {
  for (const int key : {0, 1, 4660, 13107, 21845, 32767}) {
    for (const double roll : {0.0, 33.0}) {
      const auto scene =
          Tag(key, 30, 20, roll, 1.6, 2,
              static_cast<std::uint64_t>(key) * 7 + static_cast<std::uint64_t>(roll));
      const ModelReading r =
          ReadThroughModel(scene.bgr, ChromaUpsampling::kNone, TrueCorners(scene.truth[0]));
      ASSERT_TRUE(r.fit.ok) << r.error;
      ASSERT_EQ(RefuseCodeword(r), "") << "key " << key << " roll " << roll;
      EXPECT_EQ(r.decision.winner->value(), key);
      EXPECT_NEAR(r.fit.luma_blur.major, 1.6, 0.6) << key;
      EXPECT_NEAR(r.fit.luma_blur.minor, 1.6, 0.6) << key;
    }
  }
}

// A 24 px tag saved as a 4:2:0 JPEG, read on corners a pixel off each way: the corners come back
// to within a few tenths of a pixel and the key is read.
TEST(ModelReader, RefinesCornersAPixelOffAndReadsA24PxJpeg) {
  const auto scene = Tag(20301, 24, 25, 40, 0.7, 2, 5);
  const cv::Mat jpeg = Jpeg420(scene.bgr, 85);
  Corners start = TrueCorners(scene.truth[0]);
  const cv::Point2d offsets[4] = {{0.8, -0.6}, {-0.7, -0.5}, {0.6, 0.9}, {-0.9, 0.4}};
  for (std::size_t k = 0; k < 4; ++k) start[k] += offsets[k];
  const ModelReading r = ReadThroughModel(jpeg, ChromaUpsampling::kBoth, start);
  ASSERT_TRUE(r.fit.ok) << r.error;
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_LT(cv::norm(r.fit.corners[k] - scene.truth[0].corners[k]), 0.4) << "corner " << k;
  }
  ASSERT_EQ(RefuseCodeword(r), "");
  EXPECT_EQ(r.decision.winner->value(), 20301);
}

// The detector skips the model for squares the corner refinement could never bring to kMinSidePx;
// that rests on the refinement moving no corner further than MaxCornerShiftPx. Started 3 px off,
// past that bound, the corners stop at it; and a square below the reachable size is refused
// without a model read or a turn of the frame's budget.
TEST(ModelReader, CornersMoveNoFurtherThanTheBoundTheSizeCheckRestsOn) {
  const auto scene = Tag(4242, 22, 20, 15, 0.8, 1, 3);
  Corners start = TrueCorners(scene.truth[0]);
  const cv::Point2d offsets[4] = {{3, -2}, {-3, -2}, {2.5, 3}, {-3, 2}};
  for (std::size_t k = 0; k < 4; ++k) start[k] += offsets[k];
  const double side =
      stage::MeanSidePx(stage::HomographyFromQuad({start[0], start[1], start[2], start[3]}));
  const ModelReading r = ReadThroughModel(scene.bgr, ChromaUpsampling::kNone, start);
  ASSERT_TRUE(r.fit.ok) << r.error;
  EXPECT_GT(r.fit.corner_shift, 0.5);  // it did move them
  EXPECT_LE(r.fit.corner_shift, MaxCornerShiftPx(side) + 1e-9);

  const auto small = Tag(4242, 12, 0, 0, 0.8, 1, 3);
  const Corners c = TrueCorners(small.truth[0]);
  stage::ModelBudget budget(1);
  const stage::CandidateReading read = stage::ReadCandidate(
      small.bgr, ChromaUpsampling::kNone, {c[0], c[1], c[2], c[3]}, {}, {}, &budget);
  EXPECT_FALSE(read.reading.payload.key);
  EXPECT_FALSE(read.times.model_read);
  EXPECT_EQ(read.reading.payload.error, "model: square too small to read its codeword");
  EXPECT_TRUE(budget.take());  // still there
}

// A phone's unsharp mask on luma (over- and undershoot at every edge): still read.
TEST(ModelReader, ReadsASharpenedTag) {
  const auto scene = Tag(777, 36, 10, 5, 1.0, 1, 9);
  cv::Mat ycrcb;
  cv::cvtColor(scene.bgr, ycrcb, cv::COLOR_BGR2YCrCb);
  std::vector<cv::Mat> planes;
  cv::split(ycrcb, planes);
  cv::Mat luma, soft;
  planes[0].convertTo(luma, CV_32F);
  cv::GaussianBlur(luma, soft, {}, 1.0);
  luma += 1.2 * (luma - soft);
  luma.convertTo(planes[0], CV_8U);
  cv::merge(planes, ycrcb);
  cv::Mat sharpened;
  cv::cvtColor(ycrcb, sharpened, cv::COLOR_YCrCb2BGR);
  const ModelReading r =
      ReadThroughModel(sharpened, ChromaUpsampling::kNone, TrueCorners(scene.truth[0]));
  ASSERT_TRUE(r.fit.ok) << r.error;
  ASSERT_EQ(RefuseCodeword(r), "");
  EXPECT_EQ(r.decision.winner->value(), 777);
}

// The excess (how much worse the winner explains the samples than the best free labelling) is
// judged as the lead is: in noise units, or else counted in independent chroma samples. A real
// reading's excess is set by hand to reach each side of the rule.
TEST(ModelReader, AnExcessIsCountedInIndependentSamplesAsTheLeadIs) {
  ModelReading r = ReadingToJudge();
  ASSERT_TRUE(r.fit.ok) << r.error;
  ASSERT_EQ(RefuseCodeword(r), "");
  r.fit.chroma_correlation = {0, 0};  // independent residuals: the noise-unit rule alone
  r.decision.excess = kMaxExcess * 1.5;
  EXPECT_EQ(RefuseCodeword(r), kRefusedForExcess);
  r.fit.chroma_correlation = {0.6, 0.6};  // 16 times the variance
  const double inflation = VarianceInflation(r.fit.chroma_correlation);
  ASSERT_NEAR(inflation, 16, 1e-9);
  ASSERT_GE(r.decision.lead / inflation, kMinIndependentLead);
  EXPECT_EQ(RefuseCodeword(r), "");
  r.decision.excess = kMaxIndependentExcess * inflation * 1.1;
  EXPECT_EQ(RefuseCodeword(r), kRefusedForExcess);
  r.decision.excess = kMaxExcess * 0.9;  // within the noise-unit rule, whatever the correlation
  EXPECT_EQ(RefuseCodeword(r), "");
}

TEST(ModelReader, AWinnerThatFitsAsWellAsTheFreeLabellingNeedsASmallerLead) {
  ModelReading r = ReadingToJudge();
  ASSERT_TRUE(r.fit.ok) << r.error;
  ASSERT_EQ(RefuseCodeword(r), "");
  const std::string refused_for_lead = "no codeword clearly nearest";
  r.fit.chroma_correlation = {0.6, 0.6};  // 16 times the variance
  const double inflation = VarianceInflation(r.fit.chroma_correlation);
  ASSERT_NEAR(inflation, 16, 1e-9);
  ASSERT_LT(kMinIndependentLeadOfAFit, kMinIndependentLead);
  // Between the two least independent leads, and past kMinLead in noise units.
  r.decision.lead = inflation * (kMinIndependentLeadOfAFit + kMinIndependentLead) / 2;
  ASSERT_GE(r.decision.lead, kMinLead);
  r.decision.excess = kMaxExcess * 0.5;  // the winner fits
  EXPECT_EQ(RefuseCodeword(r), "");
  r.decision.excess = kMaxExcess * 1.5;  // it does not, though the excess rule lets it pass
  ASSERT_LE(r.decision.excess / inflation, kMaxIndependentExcess);
  EXPECT_EQ(RefuseCodeword(r), refused_for_lead);
  r.decision.excess = kMaxExcess * 0.5;
  r.decision.lead = inflation * kMinIndependentLeadOfAFit * 0.9;  // fits, but leads too little
  EXPECT_EQ(RefuseCodeword(r), refused_for_lead);
}

// Where wrong winners lead most, on squares narrow one way (small, or steeply tilted), a winner
// that fits needs the larger lead. A real reading's corners are squeezed by hand across
// kNarrowExtentPx.
TEST(ModelReader, AWinnerOnANarrowSquareNeedsTheLargerLead) {
  ModelReading r = ReadingToJudge();
  ASSERT_TRUE(r.fit.ok) << r.error;
  ASSERT_EQ(RefuseCodeword(r), "");
  ASSERT_FALSE(IsNarrow(r.fit.corners));
  r.fit.chroma_correlation = {0.6, 0.6};  // 16 times the variance: kMinLead is passed below
  const double inflation = VarianceInflation(r.fit.chroma_correlation);
  r.decision.excess = kMaxNarrowExcess * 0.5;  // the winner fits, by either square's limit
  ASSERT_LT(kMinIndependentLeadOfAFit, kMinIndependentLeadOfANarrowFit);
  r.decision.lead = inflation * (kMinIndependentLeadOfAFit + kMinIndependentLeadOfANarrowFit) / 2;
  ASSERT_GE(r.decision.lead, kMinLead);
  EXPECT_EQ(RefuseCodeword(r), "");
  // The same corners squeezed towards their centre line, across one pair of sides, to a little
  // under kNarrowExtentPx and a little over.
  const Corners as_read = r.fit.corners;
  r.fit.corners = SqueezedAcross(as_read, kNarrowExtentPx * 0.9);
  ASSERT_TRUE(IsNarrow(r.fit.corners));
  EXPECT_EQ(RefuseCodeword(r), "no codeword clearly nearest");
  r.decision.lead = inflation * kMinIndependentLeadOfANarrowFit * 1.05;
  EXPECT_EQ(RefuseCodeword(r), "");
  r.decision.lead = inflation * kMinIndependentLeadOfANarrowFit * 0.98;
  EXPECT_EQ(RefuseCodeword(r), "no codeword clearly nearest");
  // A winner that does not fit is refused on a narrow square, even where its excess counted in
  // independent samples would let it pass elsewhere.
  r.decision.lead = inflation * kMinIndependentLeadOfANarrowFit * 2;
  r.decision.excess = kMaxExcess * 1.5;
  ASSERT_LE(r.decision.excess / inflation, kMaxIndependentExcess);
  EXPECT_EQ(RefuseCodeword(r), kRefusedForExcess);
  r.decision.excess = kMaxNarrowExcess * 0.5;
  r.decision.lead = inflation * (kMinIndependentLeadOfAFit + kMinIndependentLeadOfANarrowFit) / 2;
  r.fit.corners = SqueezedAcross(as_read, kNarrowExtentPx * 1.1);
  ASSERT_FALSE(IsNarrow(r.fit.corners));
  EXPECT_EQ(RefuseCodeword(r), "");
}

// On a narrow square the winner must explain the samples within kMaxNarrowExcess of the free
// labelling, however far it leads; elsewhere kMaxExcess (and the excess in independent samples)
// still applies. A real reading's corners are squeezed by hand as above.
TEST(ModelReader, AWinnerOnANarrowSquareMustFitWhateverItsLead) {
  ModelReading r = ReadingToJudge();
  ASSERT_TRUE(r.fit.ok) << r.error;
  ASSERT_EQ(RefuseCodeword(r), "");
  ASSERT_LT(kMaxNarrowExcess, kMaxExcess);
  // Far past every lead rule.
  r.decision.lead = 4 * std::max(kMinLead, VarianceInflation(r.fit.chroma_correlation) *
                                               kMinIndependentLeadOfANarrowFit);
  const Corners as_read = r.fit.corners;
  const Corners narrow = SqueezedAcross(as_read, kNarrowExtentPx * 0.9);
  ASSERT_FALSE(IsNarrow(as_read));
  ASSERT_TRUE(IsNarrow(narrow));
  const double between = (kMaxNarrowExcess + kMaxExcess) / 2;
  r.decision.excess = between;
  EXPECT_EQ(RefuseCodeword(r), "");  // the square as read is not narrow
  r.fit.corners = narrow;
  EXPECT_EQ(RefuseCodeword(r), kRefusedForExcess);
  r.decision.excess = kMaxNarrowExcess * 1.05;
  EXPECT_EQ(RefuseCodeword(r), kRefusedForExcess);
  r.decision.excess = kMaxNarrowExcess * 0.95;
  EXPECT_EQ(RefuseCodeword(r), "");
}

// Under kLumaNoiseFloor (two 8-bit code values) the lead is counted as if the luminance noise were
// the floor: a lead that passes at the floor is refused when the same fit claims a noise of a
// third of it, and counted in full at the floor and above.
TEST(ModelReader, ALeadIsCountedAtTheLuminanceNoiseFloor) {
  EXPECT_NEAR(kLumaNoiseFloor * 255, 2, 1e-12);
  ModelReading r = ReadingToJudge();
  ASSERT_TRUE(r.fit.ok) << r.error;
  ASSERT_EQ(RefuseCodeword(r), "");
  r.fit.luma_noise = kLumaNoiseFloor;
  EXPECT_DOUBLE_EQ(CountedLead(r), r.decision.lead);
  r.fit.luma_noise = kLumaNoiseFloor * 2;
  EXPECT_DOUBLE_EQ(CountedLead(r), r.decision.lead);
  // A lead 4 times what every rule asks passes at the floor and fails at a third of it (1/9).
  r.decision.lead =
      4 * std::max(kMinLead, VarianceInflation(r.fit.chroma_correlation) * kMinIndependentLead);
  r.fit.luma_noise = kLumaNoiseFloor;
  EXPECT_EQ(RefuseCodeword(r), "");
  r.fit.luma_noise = kLumaNoiseFloor / 3;
  EXPECT_NEAR(CountedLead(r), r.decision.lead / 9, 1e-9 * r.decision.lead);
  EXPECT_EQ(RefuseCodeword(r), "no codeword clearly nearest");
}

// A decision statistic that is not a number (a fit gone wrong) refuses the winner.
TEST(ModelReader, AStatisticThatIsNotANumberRefuses) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const ModelReading accepted = ReadingToJudge();
  ASSERT_TRUE(accepted.fit.ok) << accepted.error;
  ASSERT_EQ(RefuseCodeword(accepted), "");
  ModelReading r = accepted;
  r.decision.lead = nan;
  EXPECT_NE(RefuseCodeword(r), "");
  r = accepted;
  r.fit.luma_noise = nan;
  EXPECT_NE(RefuseCodeword(r), "");
  r = accepted;
  r.decision.excess = nan;
  EXPECT_NE(RefuseCodeword(r), "");
  r = accepted;
  r.decision.chroma_deficit = nan;
  EXPECT_NE(RefuseCodeword(r), "");
}

TEST(ModelReader, ABlackSquareWithoutElementsGivesNoKey) {
  cv::Mat bgr(120, 120, CV_8UC3, cv::Scalar(235, 235, 235));
  cv::rectangle(bgr, {40, 40}, {79, 79}, cv::Scalar(25, 25, 25), cv::FILLED);
  cv::GaussianBlur(bgr, bgr, {}, 1.2);
  const Corners square = {cv::Point2d(39.5, 39.5), {79.5, 39.5}, {79.5, 79.5}, {39.5, 79.5}};
  const ModelReading r = ReadThroughModel(bgr, ChromaUpsampling::kNone, square);
  ASSERT_TRUE(r.fit.ok);
  EXPECT_NE(RefuseCodeword(r), "");
}

// Squares that are not tags (colourful blotches in a black square with a white margin) are
// refused.
TEST(ModelReader, ColourfulNonTagsAreRefused) {
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
    const Corners square = {cv::Point2d(39.5, 39.5), {79.5, 39.5}, {79.5, 79.5}, {39.5, 79.5}};
    const ModelReading r = ReadThroughModel(bgr, ChromaUpsampling::kNone, square);
    ASSERT_TRUE(r.fit.ok);
    EXPECT_NE(RefuseCodeword(r), "") << "trial " << trial;
  }
}

TEST(ModelReader, LargeSquaresAndSquaresOffTheImageAreNotModelled) {
  const cv::Mat bgr(400, 400, CV_8UC3, cv::Scalar(200, 200, 200));
  std::string error;
  const Corners large = {cv::Point2d(50, 50), {250, 50}, {250, 250}, {50, 250}};
  EXPECT_FALSE(FitModel(bgr, ChromaUpsampling::kNone, large, &error).fit.ok);
  const Corners outside = {cv::Point2d(-500, -500), {-460, -500}, {-460, -460}, {-500, -460}};
  EXPECT_FALSE(FitModel(bgr, ChromaUpsampling::kNone, outside, &error).fit.ok);
}

}  // namespace
}  // namespace pintag::reading
