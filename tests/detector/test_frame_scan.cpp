// Stage 1, the one pass over the frame: each of its outputs is what the separate computation of
// it gives.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <opencv2/core.hpp>
#include <vector>

#include "candidates/frame_scan.hpp"
#include "candidates/quads.hpp"

namespace pintag::stage {
namespace {

// Random colours, with warm and reddish patches so that both red levels have runs; odd sizes so
// that the half-resolution image drops a row and a column.
cv::Mat NoisyFrame() {
  cv::Mat bgr(201, 301, CV_8UC3);
  cv::RNG rng(7);
  rng.fill(bgr, cv::RNG::UNIFORM, 0, 256);
  bgr(cv::Rect(20, 30, 40, 25)).setTo(cv::Scalar(40, 70, 150));    // a* about 30: both levels
  bgr(cv::Rect(120, 80, 30, 30)).setTo(cv::Scalar(90, 100, 130));  // a* about 15: faint only
  return bgr;
}

bool SameRuns(const RedRuns& a, const RedRuns& b) {
  return a.size == b.size && std::equal(a.runs.begin(), a.runs.end(), b.runs.begin(), b.runs.end(),
                                        [](const RedRun& x, const RedRun& y) {
                                          return x.y == y.y && x.x0 == y.x0 && x.x1 == y.x1;
                                        });
}

// The main red level and the faint one in one scan. The faint levels tests use: nested (the
// faint table is read first and the main one only where it passes), and not nested (the faint
// level's b* bound is the stricter one).
constexpr RednessThresholds kMainLevel{20, -30};
constexpr std::array<RednessThresholds, 2> kFaintLevels = {{{12, -30}, {12, 0}}};

FrameScan ScanBothLevels(const cv::Mat& bgr, const RednessThresholds& faint,
                         bool dark_images = false) {
  FrameScanRequest both;
  both.red = kMainLevel;
  both.faint = faint;
  both.min_channel = both.dark_half = dark_images;
  return ScanFrame(bgr, both);
}

// The scan's min(R, G, B) and its half-resolution mean against the per-pixel rule.
void ExpectDarkImagesOfTheRule(const cv::Mat& bgr, const FrameScan& scan) {
  ASSERT_EQ(scan.min_channel.size(), bgr.size());
  for (int y = 0; y < bgr.rows; ++y) {
    for (int x = 0; x < bgr.cols; ++x) {
      const cv::Vec3b& p = bgr.at<cv::Vec3b>(y, x);
      ASSERT_EQ(scan.min_channel.at<std::uint8_t>(y, x), std::min({p[0], p[1], p[2]}))
          << x << ", " << y << " of " << bgr.cols << " x " << bgr.rows;
    }
  }
  ASSERT_EQ(scan.dark_half.size(), cv::Size(bgr.cols / 2, bgr.rows / 2));
  for (int y = 0; y < scan.dark_half.rows; ++y) {
    for (int x = 0; x < scan.dark_half.cols; ++x) {
      int sum = 0;
      for (int k = 0; k < 4; ++k) {
        const cv::Vec3b& p = bgr.at<cv::Vec3b>(2 * y + k / 2, 2 * x + k % 2);
        sum += std::min({p[0], p[1], p[2]});
      }
      ASSERT_EQ(scan.dark_half.at<std::uint8_t>(y, x), sum / 4) << x << ", " << y;
    }
  }
}

// The scan's runs of both levels against the per-pixel rule, pixel by pixel; `counts` gets how many
// pixels are red at each level. `path` names the lookups in a failure.
struct LevelCounts {
  int red = 0;
  int faint = 0;
};
void ExpectRunsOfTheRule(const cv::Mat& bgr, const FrameScan& scan, const RednessThresholds& faint,
                         const char* path, LevelCounts* counts) {
  const cv::Mat red = RunsToMask(scan.red), faint_red = RunsToMask(scan.faint);
  for (int y = 0; y < bgr.rows; ++y) {
    for (int x = 0; x < bgr.cols; ++x) {
      const cv::Vec3b& p = bgr.at<cv::Vec3b>(y, x);
      const bool is_red = IsRedPixel(p[2], p[1], p[0], kMainLevel);
      const bool is_faint = IsRedPixel(p[2], p[1], p[0], faint);
      ASSERT_EQ(red.at<std::uint8_t>(y, x) != 0, is_red) << x << ", " << y << " " << path;
      ASSERT_EQ(faint_red.at<std::uint8_t>(y, x) != 0, is_faint) << x << ", " << y << " " << path;
      counts->red += is_red;
      counts->faint += is_faint;
    }
  }
}

TEST(FrameScan, BothRedLevelsAreWhatTheirOwnPassesGive) {
  const cv::Mat bgr = NoisyFrame();
  const RednessThresholds main = kMainLevel;
  for (const RednessThresholds& faint : kFaintLevels) {
    const FrameScan scan = ScanBothLevels(bgr, faint);
    FrameScanRequest only_main, only_faint;
    only_main.red = main;
    only_faint.red = faint;
    EXPECT_TRUE(SameRuns(scan.red, ScanFrame(bgr, only_main).red)) << faint.min_b;
    EXPECT_TRUE(SameRuns(scan.faint, ScanFrame(bgr, only_faint).red)) << faint.min_b;
  }
}

TEST(FrameScan, EachOutputIsWhatItsOwnPassGives) {
  const cv::Mat bgr = NoisyFrame();
  const RednessThresholds main{20, -30}, faint{12, -30};
  FrameScanRequest all;
  all.red = main;
  all.faint = faint;
  all.dark_half = true;
  const FrameScan scan = ScanFrame(bgr, all);

  FrameScanRequest only_main;
  only_main.red = main;
  FrameScanRequest only_faint;
  only_faint.red = faint;
  const FrameScan main_alone = ScanFrame(bgr, only_main);
  EXPECT_TRUE(SameRuns(scan.red, main_alone.red));
  EXPECT_TRUE(SameRuns(scan.faint, ScanFrame(bgr, only_faint).red));
  EXPECT_GT(scan.faint.runs.size(), scan.red.runs.size());
  EXPECT_TRUE(main_alone.faint.runs.empty());
  EXPECT_TRUE(main_alone.dark_half.empty());
  EXPECT_TRUE(main_alone.min_channel.empty());

  // Red runs against a plain per-pixel mask of the same rule.
  cv::Mat mask = RunsToMask(scan.red);
  int disagree = 0;
  for (int y = 0; y < bgr.rows; ++y) {
    for (int x = 0; x < bgr.cols; ++x) {
      const cv::Vec3b& p = bgr.at<cv::Vec3b>(y, x);
      disagree += IsRedPixel(p[2], p[1], p[0], main) != (mask.at<std::uint8_t>(y, x) != 0);
    }
  }
  EXPECT_EQ(disagree, 0);

  // min(R, G, B), kept for the half-resolution image and for the quad stage, against the plain
  // per-pixel rule; asked for alone it is the same, without the half-resolution image.
  FrameScanRequest only_min = only_main;
  only_min.min_channel = true;
  const FrameScan min_alone = ScanFrame(bgr, only_min);
  EXPECT_TRUE(min_alone.dark_half.empty());
  for (const cv::Mat& kept : {scan.min_channel, min_alone.min_channel}) {
    ASSERT_EQ(kept.size(), bgr.size());
    for (int y = 0; y < bgr.rows; ++y) {
      for (int x = 0; x < bgr.cols; ++x) {
        const cv::Vec3b& p = bgr.at<cv::Vec3b>(y, x);
        ASSERT_EQ(kept.at<std::uint8_t>(y, x), std::min({p[0], p[1], p[2]})) << x << ", " << y;
      }
    }
  }

  const cv::Mat dark = MinChannel(bgr, cv::Rect(0, 0, bgr.cols, bgr.rows));
  ASSERT_EQ(scan.dark_half.rows, bgr.rows / 2);
  ASSERT_EQ(scan.dark_half.cols, bgr.cols / 2);
  for (int y = 0; y < scan.dark_half.rows; ++y) {
    for (int x = 0; x < scan.dark_half.cols; ++x) {
      const int sum =
          dark.at<std::uint8_t>(2 * y, 2 * x) + dark.at<std::uint8_t>(2 * y, 2 * x + 1) +
          dark.at<std::uint8_t>(2 * y + 1, 2 * x) + dark.at<std::uint8_t>(2 * y + 1, 2 * x + 1);
      ASSERT_EQ(scan.dark_half.at<std::uint8_t>(y, x), sum / 4) << x << ", " << y;
    }
  }
}

// The scan skips the red-table lookups of 16 pixels at a time where none can be red. On a grey
// ground (varying, so that the dark images of skipped blocks are checked too) nearly every block
// is skipped; patches of red and of faint-only red start and end inside blocks, on their edges,
// at the row's start and in its last partial block.
TEST(FrameScan, RunsAroundSkippedBlocksAreThoseOfTheRule) {
  cv::Mat bgr(24, 203, CV_8UC3);
  for (int y = 0; y < bgr.rows; ++y) {
    for (int x = 0; x < bgr.cols; ++x) {
      const auto grey = static_cast<std::uint8_t>(60 + (7 * x + 13 * y) % 120);
      bgr.at<cv::Vec3b>(y, x) = {grey, grey, grey};
    }
  }
  const cv::Scalar both_levels(40, 70, 150), faint_only(90, 95, 130);  // BGR
  const std::array<std::array<int, 3>, 9> patches = {{{0, 0, 5},       // at the row's start
                                                      {1, 15, 17},     // across a block edge
                                                      {2, 16, 32},     // exactly one block
                                                      {3, 31, 49},     // block edge to block edge
                                                      {4, 5, 6},       // one pixel
                                                      {5, 190, 203},   // into the partial block
                                                      {6, 40, 41},
                                                      {7, 63, 64},
                                                      {8, 100, 180}}};
  for (int band = 0; band < 2; ++band) {
    for (const auto& [row, x0, x1] : patches) {
      bgr(cv::Rect(x0, 2 * row + band, x1 - x0, 1)).setTo(band == 0 ? both_levels : faint_only);
    }
  }
  for (const RednessThresholds& faint : kFaintLevels) {
    const FrameScan scan = ScanBothLevels(bgr, faint, /*dark_images=*/true);
    ExpectDarkImagesOfTheRule(bgr, scan);
    LevelCounts counts;
    ASSERT_NO_FATAL_FAILURE(ExpectRunsOfTheRule(bgr, scan, faint, "", &counts));
    EXPECT_GT(counts.red, 0);
    EXPECT_GT(counts.faint, counts.red) << "faint b* >= " << faint.min_b;
  }
}

// Rows shorter than one block, one block exactly and just over: no vector loop, or one and a
// pixel or more left over for the scalar tail.
TEST(FrameScan, NarrowFramesGiveTheDarkImagesOfTheRule) {
  for (const int width : {1, 2, 7, 15, 16, 17, 31, 33}) {
    cv::Mat bgr(6, width, CV_8UC3);
    cv::RNG rng(static_cast<std::uint64_t>(width));
    rng.fill(bgr, cv::RNG::UNIFORM, 0, 256);
    for (const RednessThresholds& faint : kFaintLevels) {
      ExpectDarkImagesOfTheRule(bgr, ScanBothLevels(bgr, faint, /*dark_images=*/true));
    }
  }
}

// Every (G, B) at the edge of each level: R one below the least red R of the main level, at it,
// and the same for the faint level (clamped to 0 … 255), so every table entry decides a pixel. On
// an AVX2 machine the gathered lookups and the one-by-one lookups must both give the rule; on
// others both requests take the one-by-one path.
TEST(FrameScan, EveryTableEntryGivesTheRuleWithEitherLookup) {
  const RedTable& main_table = RedTable::For(kMainLevel);
  for (const RednessThresholds& faint : kFaintLevels) {
    const RedTable& faint_table = RedTable::For(faint);
    cv::Mat bgr(1024, 256, CV_8UC3);  // row 4 G + k: B along x, k picks which R
    for (int g = 0; g < 256; ++g) {
      for (int k = 0; k < 4; ++k) {
        for (int b = 0; b < 256; ++b) {
          const int index = (g << 8) | b;
          const int least = (k < 2 ? main_table : faint_table).leastRedR()[index];
          const int r = std::clamp(least - 1 + k % 2, 0, 255);
          bgr.at<cv::Vec3b>(4 * g + k, b) = {static_cast<std::uint8_t>(b),
                                             static_cast<std::uint8_t>(g),
                                             static_cast<std::uint8_t>(r)};
        }
      }
    }
    for (const RedLookups lookups : {RedLookups::kFastest, RedLookups::kOneByOne}) {
      FrameScanRequest request;
      request.red = kMainLevel;
      request.faint = faint;
      request.lookups = lookups;
      LevelCounts counts;
      ASSERT_NO_FATAL_FAILURE(
          ExpectRunsOfTheRule(bgr, ScanFrame(bgr, request), faint,
                              lookups == RedLookups::kFastest ? "fastest" : "one by one", &counts));
      // Half of the rows sit at a least R: tens of thousands of pixels of each level.
      EXPECT_GT(counts.red, 10000);
      EXPECT_GT(counts.faint, 10000);
    }
  }
  RecordProperty("gathers_red_lookups", GathersRedLookups() ? "yes" : "no");
}

// The prefilter's boundary: a red pixel whose lead 4 (R − G) + (B − G) is exactly the least of its
// level, alone in a block of grey (lead 0), at each of the 16 places of a block, must be found by
// both lookups, at the main level alone and as the faint level of a scan.
TEST(FrameScan, APixelAtTheLeastLeadAloneInItsBlockIsRed) {
  std::vector<RednessThresholds> levels = {kMainLevel, kFaintLevels[0], kFaintLevels[1]};
  for (const RednessThresholds& level : levels) {
    const RedTable& table = RedTable::For(level);
    cv::Vec3b at_least{};  // BGR
    bool found = false;
    for (int index = 0; index < (1 << 16) && !found; ++index) {
      const int r = table.leastRedR()[index], g = index >> 8, b = index & 0xFF;
      if (r < 256 && 4 * (r - g) + (b - g) == table.leastRedLead()) {
        at_least = {static_cast<std::uint8_t>(b), static_cast<std::uint8_t>(g),
                    static_cast<std::uint8_t>(r)};
        found = true;
      }
    }
    ASSERT_TRUE(found) << level.min_a << ", " << level.min_b;
    ASSERT_TRUE(IsRedPixel(at_least[2], at_least[1], at_least[0], level));
    cv::Mat bgr(16, 64, CV_8UC3, cv::Scalar(128, 128, 128));
    for (int k = 0; k < 16; ++k) bgr.at<cv::Vec3b>(k, 16 + k) = at_least;  // row k: place k
    for (const RedLookups lookups : {RedLookups::kFastest, RedLookups::kOneByOne}) {
      FrameScanRequest alone;
      alone.red = level;
      alone.lookups = lookups;
      FrameScanRequest as_faint = alone;
      as_faint.red = kMainLevel;
      as_faint.faint = level;
      for (const RedRuns& runs : {ScanFrame(bgr, alone).red, ScanFrame(bgr, as_faint).faint}) {
        ASSERT_EQ(runs.runs.size(), 16U) << level.min_a << ", " << level.min_b;
        for (int k = 0; k < 16; ++k) {
          const RedRun& run = runs.runs[static_cast<std::size_t>(k)];
          EXPECT_EQ(run.y, k);
          EXPECT_EQ(run.x0, 16 + k);
          EXPECT_EQ(run.x1, 16 + k);
        }
      }
    }
  }
}

// Random frames of many widths, with every output asked for: the two lookups give the same runs
// and dark images.
TEST(FrameScan, BothLookupsGiveTheSameScan) {
  for (const int width : {15, 16, 17, 47, 48, 300, 1021}) {
    cv::Mat bgr(9, width, CV_8UC3);
    cv::RNG rng(static_cast<std::uint64_t>(width) + 100);
    rng.fill(bgr, cv::RNG::UNIFORM, 0, 256);
    bgr(cv::Rect(0, 2, width, 3)).setTo(cv::Scalar(40, 70, 150));  // red rows, end to end
    for (const RednessThresholds& faint : kFaintLevels) {
      FrameScanRequest request;
      request.red = kMainLevel;
      request.faint = faint;
      request.dark_half = true;
      const FrameScan fastest = ScanFrame(bgr, request);
      request.lookups = RedLookups::kOneByOne;
      const FrameScan one_by_one = ScanFrame(bgr, request);
      EXPECT_TRUE(SameRuns(fastest.red, one_by_one.red)) << width;
      EXPECT_TRUE(SameRuns(fastest.faint, one_by_one.faint)) << width;
      EXPECT_EQ(cv::norm(fastest.min_channel, one_by_one.min_channel, cv::NORM_INF), 0) << width;
      EXPECT_EQ(cv::norm(fastest.dark_half, one_by_one.dark_half, cv::NORM_INF), 0) << width;
      ExpectDarkImagesOfTheRule(bgr, one_by_one);
    }
  }
}

}  // namespace
}  // namespace pintag::stage
