// The rules on top of the codec that decide whether a direct reading's key is kept
// (reading/read_tag.hpp): a reading that needed recovery must have read its other bits clearly,
// and one whose unknown cells are spread over several elements is left to the model reader.

#include <gtest/gtest.h>

#include "pintag/codec/cells.hpp"
#include "reading/read_tag.hpp"

namespace pintag::stage {
namespace {

// What the direct reader would hand over for a clean read of `key`, every bit at `margin`.
OrientationResult CleanReading(int key, double margin) {
  const TagCells cells = EncodeCells(TagKey(static_cast<std::uint16_t>(key)));
  OrientationResult o;
  o.ok = true;
  for (int e = 0; e < kElements; ++e) {
    for (int g = 0; g < kGreenSectors; ++g) {
      o.reading.green[e][g] = cells.green[e][g] ? Bit::kOne : Bit::kZero;
    }
    for (int q = 0; q < kRedQuadrants; ++q) {
      o.reading.red[e][q] = cells.red[e][q] ? Bit::kOne : Bit::kZero;
    }
  }
  o.min_known_margin = margin;
  return o;
}

void CoverElement(OrientationResult& o, int element) {
  o.reading.green[element].fill(Bit::kUnknown);
  o.reading.red[element].fill(Bit::kUnknown);
}

TEST(ReadTag, ACleanReadingNeedsNoRecoveryAndHasNoUnknownElement) {
  const OrientationResult o = CleanReading(22395, 0.9);
  const PayloadResult payload = DecodeReading(o);
  ASSERT_TRUE(payload.key);
  EXPECT_EQ(payload.key->value(), 22395);
  EXPECT_FALSE(NeededRecovery(payload));
  EXPECT_EQ(ElementsWithUnknownCells(o), 0);
}

TEST(ReadTag, ACoveredElementIsRecoveredAndCountsAsOneElement) {
  // The two payload copies are laid out so that any one element may be lost: the direct reader
  // keeps such a key itself (the model, which expects a whole tag, would refuse it).
  for (const int key : {22395, 18299, 0, 32767}) {
    for (int element = 0; element < kElements; ++element) {
      OrientationResult o = CleanReading(key, 0.9);
      CoverElement(o, element);
      const PayloadResult payload = DecodeReading(o);
      ASSERT_TRUE(payload.key) << "key " << key << ", element " << element << " covered";
      EXPECT_EQ(payload.key->value(), key);
      EXPECT_TRUE(NeededRecovery(payload));
      EXPECT_EQ(ElementsWithUnknownCells(o), 1);
    }
  }
}

TEST(ReadTag, UnknownCellsAreCountedByTheElementsTheyLieIn) {
  OrientationResult o = CleanReading(22395, 0.9);
  o.reading.green[0][3] = Bit::kUnknown;
  o.reading.green[0][5] = Bit::kUnknown;
  EXPECT_EQ(ElementsWithUnknownCells(o), 1);
  o.reading.red[3][1] = Bit::kUnknown;
  EXPECT_EQ(ElementsWithUnknownCells(o), 2);
  o.reading.red[1][0] = Bit::kUnknown;
  o.reading.green[2][7] = Bit::kUnknown;
  EXPECT_EQ(ElementsWithUnknownCells(o), 4);
}

TEST(ReadTag, ARecoveredReadingWithAWeakBitIsRefused) {
  OrientationResult o = CleanReading(22395, kRecoveredReadingMinMargin - 0.05);
  CoverElement(o, 2);
  const PayloadResult payload = DecodeReading(o);
  EXPECT_FALSE(payload.key);
  EXPECT_FALSE(payload.error.empty());
  // The same reading read clearly keeps its key.
  o.min_known_margin = kRecoveredReadingMinMargin + 0.05;
  EXPECT_TRUE(DecodeReading(o).key);
}

}  // namespace
}  // namespace pintag::stage
