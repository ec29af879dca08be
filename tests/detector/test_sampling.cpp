// Stage 5: cells sampled through the homography read the palette's b*.

#include <gtest/gtest.h>

#include "homography.hpp"
#include "pintag/codec/cells.hpp"
#include "reading/sampling.hpp"
#include "synthetic.hpp"

namespace pintag::stage {
namespace {

TEST(Sampling, CellsOfAWarpedTagHaveTheirPaletteColours) {
  testing::SyntheticOptions o;
  const int key = 21845;
  const auto scene =
      testing::MakeScene({{.key = key, .square_px = 110, .tilt_deg = 30, .roll_deg = 40}}, o);
  Quad quad;
  for (int i = 0; i < 4; ++i) quad[i] = scene.truth[0].corners[i];
  const CellSamples samples = SampleCells(scene.bgr, HomographyFromQuad(quad));
  const TagCells truth = EncodeCells(TagKey(key));
  for (int e = 0; e < kElements; ++e) {
    for (int s = 0; s < kGreenSectors; ++s) {
      const CellSample& c = samples.green[e][s];
      ASSERT_TRUE(c.valid);
      EXPECT_LT(c.a, -25);                               // green: −42 / −35
      EXPECT_NEAR(c.b, truth.green[e][s] ? 66 : -7, 8);  // b* of the two greens
    }
    for (int q = 0; q < kRedQuadrants; ++q) {
      const CellSample& c = samples.red[e][q];
      EXPECT_GT(c.a, 50);  // red: +62 / +72
      EXPECT_NEAR(c.b, truth.red[e][q] ? 68 : -8, 8);
    }
  }
}

TEST(Sampling, OutsideTheImageIsInvalid) {
  const cv::Mat bgr(50, 50, CV_8UC3, cv::Scalar(255, 255, 255));
  const Quad quad = {cv::Point2d(30, 30), {90, 30}, {90, 90}, {30, 90}};
  const CellSamples samples = SampleCells(bgr, HomographyFromQuad(quad));
  EXPECT_FALSE(samples.green[2][0].valid);
}

}  // namespace
}  // namespace pintag::stage
