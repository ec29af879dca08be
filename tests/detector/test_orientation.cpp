// Stage 6a: orientation and the tag's own thresholds, from cell values.

#include <gtest/gtest.h>

#include "reading/orientation.hpp"

namespace pintag::stage {
namespace {

// Ideal samples of `key` with C0 at element `c0` of the sampled frame; b* scaled and shifted like
// a colour cast would.
CellSamples Samples(int key, int c0, double gain = 1, double shift = 0) {
  const TagCells cells = EncodeCells(TagKey(key));
  CellSamples canonical;
  for (int e = 0; e < kElements; ++e) {
    for (int s = 0; s < kGreenSectors; ++s)
      canonical.green[e][s] = {-40, (cells.green[e][s] ? 66 : -7) * gain + shift, 2, true};
    for (int q = 0; q < kRedQuadrants; ++q)
      canonical.red[e][q] = {65, (cells.red[e][q] ? 68 : -8) * gain + shift, 2, true};
  }
  // Undo the rotation the reader will apply: sampled element (e + c0) is canonical e.
  return RotateCells(canonical, -c0);
}

TEST(Orientation, RotateCellsMatchesTheCodecsRotateReading) {
  CellReading reading;
  const TagCells cells = EncodeCells(TagKey(12345));
  for (int e = 0; e < kElements; ++e) {
    for (int s = 0; s < kGreenSectors; ++s)
      reading.green[e][s] = cells.green[e][s] ? Bit::kOne : Bit::kZero;
    for (int q = 0; q < kRedQuadrants; ++q)
      reading.red[e][q] = cells.red[e][q] ? Bit::kOne : Bit::kZero;
  }
  for (int r = 0; r < 4; ++r) {
    const CellReading a = RotateReading(reading, r), b = RotateCells(reading, r);
    EXPECT_EQ(a.green, b.green);
    EXPECT_EQ(a.red, b.red);
  }
}

TEST(Orientation, FindsC0AtEveryRotationUnderCasts) {
  for (int c0 = 0; c0 < 4; ++c0) {
    for (auto [gain, shift] : {std::pair{1.0, 0.0}, {0.6, 15.0}, {0.8, -12.0}}) {
      const OrientationResult r = ReadOrientation(Samples(777, c0, gain, shift), {});
      ASSERT_TRUE(r.ok) << r.error;
      EXPECT_EQ(r.quarter_turns, c0);
      EXPECT_EQ(r.unknown, 0);
      EXPECT_EQ(DecodeCells(r.reading).key, TagKey(777));
    }
  }
}

TEST(Orientation, HiddenC0StillOrients) {
  for (int c0 = 0; c0 < 4; ++c0) {
    CellSamples s = Samples(30000, c0);
    for (auto& cell : s.green[c0]) cell.a = 5;  // beige cover: neither green nor red
    for (auto& cell : s.red[c0]) cell.a = 5;
    const OrientationResult r = ReadOrientation(s, {});
    ASSERT_TRUE(r.ok) << r.error;
    EXPECT_EQ(r.quarter_turns, c0);
    EXPECT_EQ(r.unknown, 12);
    EXPECT_EQ(DecodeCells(r.reading).key, TagKey(30000));
  }
}

TEST(Orientation, BitsNearTheThresholdAreUnknownNotGuessed) {
  CellSamples s = Samples(1234, 0);
  s.green[1][3].b = 30;  // exactly between the levels
  const OrientationResult r = ReadOrientation(s, {});
  ASSERT_TRUE(r.ok);
  EXPECT_EQ(r.reading.green[1][3], Bit::kUnknown);
  EXPECT_NEAR(r.margins.green[1][3], 0, 0.1);
}

TEST(Orientation, NoContrastNoOrientation) {
  CellSamples s = Samples(1234, 0, 0.1);  // the 0 and 1 levels 7 b* apart
  EXPECT_FALSE(ReadOrientation(s, {}).ok);
  CellSamples grey;
  EXPECT_FALSE(ReadOrientation(grey, {}).ok);
}

}  // namespace
}  // namespace pintag::stage
