// Stage 6b: payload and parity go through the codec, which never guesses.

#include <gtest/gtest.h>

#include "reading/payload.hpp"

namespace pintag::stage {
namespace {

CellReading Read(int key) {
  const TagCells cells = EncodeCells(TagKey(key));
  CellReading r;
  for (int e = 0; e < kElements; ++e) {
    for (int s = 0; s < kGreenSectors; ++s)
      r.green[e][s] = cells.green[e][s] ? Bit::kOne : Bit::kZero;
    for (int q = 0; q < kRedQuadrants; ++q) r.red[e][q] = cells.red[e][q] ? Bit::kOne : Bit::kZero;
  }
  return r;
}

TEST(Payload, DecodesCleanAndOneElementMissingReadings) {
  for (int key : {0, 1, 4242, 32767}) {
    EXPECT_EQ(DecodePayload(Read(key)).key, TagKey(static_cast<std::uint16_t>(key)));
    for (int e = 0; e < 4; ++e) {
      CellReading r = Read(key);
      for (Bit& b : r.green[e]) b = Bit::kUnknown;
      for (Bit& b : r.red[e]) b = Bit::kUnknown;
      const PayloadResult p = DecodePayload(r);
      ASSERT_TRUE(p.key) << key << " element " << e << ": " << p.error;
      EXPECT_EQ(p.key->value(), key);
      EXPECT_EQ(p.bits_from_second_copy, 8);
      EXPECT_TRUE(p.bit_from_parity);
    }
  }
}

TEST(Payload, RejectsEverySingleFlippedBit) {
  const CellReading good = Read(12345);
  for (int e = 0; e < 4; ++e) {
    for (int s = 0; s < kGreenSectors; ++s) {
      CellReading r = good;
      r.green[e][s] = r.green[e][s] == Bit::kOne ? Bit::kZero : Bit::kOne;
      EXPECT_FALSE(DecodePayload(r).key);
    }
    for (int q = 0; q < kRedQuadrants; ++q) {
      CellReading r = good;
      r.red[e][q] = r.red[e][q] == Bit::kOne ? Bit::kZero : Bit::kOne;
      EXPECT_FALSE(DecodePayload(r).key);
    }
  }
}

TEST(Payload, RejectsARotatedReading) {
  EXPECT_FALSE(DecodePayload(RotateReading(Read(12345), 1)).key);
}

}  // namespace
}  // namespace pintag::stage
