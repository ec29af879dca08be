// Round trips through the format-v1 cell layout, and the decoder's refusal of bad readings.
// The test keeps its own map from code bits to cells, written from DESIGN.md §2, so it checks the
// codec against the spec rather than against itself.

#include "pintag/codec/cells.hpp"

#include <gtest/gtest.h>

#include "pintag/codec/hamming.hpp"

namespace pintag {
namespace {

CellReading ToReading(const TagCells& cells) {
  CellReading reading;
  for (int e = 0; e < kElements; ++e) {
    for (int s = 0; s < kGreenSectors; ++s)
      reading.green[e][s] = cells.green[e][s] ? Bit::kOne : Bit::kZero;
    for (int q = 0; q < kRedQuadrants; ++q)
      reading.red[e][q] = cells.red[e][q] ? Bit::kOne : Bit::kZero;
  }
  return reading;
}

Bit Flip(Bit bit) {
  return bit == Bit::kOne ? Bit::kZero : Bit::kOne;
}

// Code bit c: 0 … 14 data bits, 15 … 19 parity h0 … h4. Data bit i is payload bit i + 1 and h0 is
// payload bit 0; the payload's high byte sits on C0 (copy A) and C2 (copy B), the low byte on C1
// and C3, most significant bit in sector 0. h1 … h4 sit in the inner red quadrant of C0 … C3.
void FlipCodeBit(CellReading& reading, int c) {
  if (c >= 16) {
    const int element = c - 16;
    Bit& bit = reading.red[element][(element + 1) % 4];
    bit = Flip(bit);
    return;
  }
  const int payload_bit = c == 15 ? 0 : c + 1;
  for (const int high_element : {0, 2}) {
    const int element = payload_bit >= 8 ? high_element : high_element + 1;
    const int sector = payload_bit >= 8 ? 15 - payload_bit : 7 - payload_bit;
    Bit& bit = reading.green[element][sector];
    bit = Flip(bit);
  }
}

TEST(Hamming, ParityMatchesTheDefinitionBitByBit) {
  for (int key = 0; key < kKeyCount; ++key) {
    for (int j = 0; j < kParityBits; ++j) {
      int expected = 0;
      for (int i = 0; i < 15; ++i) {
        if ((kDataBitPositions[i] >> j) & 1) expected ^= (key >> i) & 1;
      }
      ASSERT_EQ((HammingParity(static_cast<std::uint16_t>(key)) >> j) & 1, expected) << key;
    }
  }
}

TEST(Hamming, DataPositionsAreTheFirstFifteenNonPowersOfTwo) {
  int next = 0;
  for (int position = 1; position <= 31 && next < 15; ++position) {
    if ((position & (position - 1)) == 0) continue;
    EXPECT_EQ(kDataBitPositions[next++], position);
  }
  EXPECT_EQ(next, 15);
}

TEST(Cells, KeyOneWorkedByHand) {
  // Key 1: data bit 0 at position 3 = 0b00011, so h0 = h1 = 1 and h2 = h3 = h4 = 0.
  // Payload P = (1 << 1) | h0 = 0x0003: C0 and C2 carry 0x00, C1 and C3 carry 0x03 (sectors 6, 7).
  const TagCells cells = EncodeCells(TagKey(1));
  for (const int e : {0, 2}) {
    for (int s = 0; s < 8; ++s) EXPECT_FALSE(cells.green[e][s]) << e << "/" << s;
  }
  for (const int e : {1, 3}) {
    for (int s = 0; s < 8; ++s) EXPECT_EQ(cells.green[e][s], s >= 6) << e << "/" << s;
  }
  // Red: C0 all 0 but its inner quadrant (1, facing bottom-right) = h1 = 1; C1 … C3 all 1 but their
  // inner quadrants (2, 3, 0) = h2, h3, h4 = 0.
  const bool expected_red[4][4] = {{false, true, false, false},
                                   {true, true, false, true},
                                   {true, true, true, false},
                                   {false, true, true, true}};
  for (int e = 0; e < 4; ++e) {
    for (int q = 0; q < 4; ++q) EXPECT_EQ(cells.red[e][q], expected_red[e][q]) << e << "/" << q;
  }
}

TEST(Cells, EveryKeyRoundTrips) {
  for (int key = 0; key < kKeyCount; ++key) {
    const DecodeResult result = DecodeCells(ToReading(EncodeCells(TagKey(key))));
    ASSERT_TRUE(result.key.has_value()) << key << ": " << ToString(result.error);
    ASSERT_EQ(result.key->value(), key);
    ASSERT_EQ(result.bits_from_second_copy, 0);
    ASSERT_FALSE(result.bit_from_parity);
  }
}

TEST(Cells, EverySingleAndDoubleCodeBitErrorIsRejected) {
  for (int key = 0; key < kKeyCount; ++key) {
    const CellReading clean = ToReading(EncodeCells(TagKey(key)));
    for (int first = 0; first < 20; ++first) {
      CellReading once = clean;
      FlipCodeBit(once, first);
      ASSERT_FALSE(DecodeCells(once).key.has_value()) << key << " bit " << first;
      for (int second = first + 1; second < 20; ++second) {
        CellReading twice = once;
        FlipCodeBit(twice, second);
        ASSERT_FALSE(DecodeCells(twice).key.has_value())
            << key << " bits " << first << "," << second;
      }
    }
  }
}

TEST(Cells, DisagreeingPayloadCopiesAreRejected) {
  for (const int key : {0, 1, 12345, 32767}) {
    for (int e = 0; e < 4; ++e) {
      for (int s = 0; s < 8; ++s) {
        CellReading reading = ToReading(EncodeCells(TagKey(key)));
        reading.green[e][s] = Flip(reading.green[e][s]);
        const DecodeResult result = DecodeCells(reading);
        EXPECT_FALSE(result.key.has_value());
        EXPECT_EQ(result.error, DecodeError::kCopiesDisagree);
      }
    }
  }
}

TEST(Cells, OrientationBitContradictionIsRejected) {
  CellReading reading = ToReading(EncodeCells(TagKey(777)));
  reading.red[2][0] = Flip(reading.red[2][0]);  // quadrant 0 of C2 is an outer quadrant
  EXPECT_EQ(DecodeCells(reading).error, DecodeError::kOrientation);
}

TEST(Cells, OneCoveredElementStillDecodesEveryKey) {
  for (int key = 0; key < kKeyCount; ++key) {
    for (int covered = 0; covered < 4; ++covered) {
      CellReading reading = ToReading(EncodeCells(TagKey(key)));
      reading.green[covered].fill(Bit::kUnknown);
      reading.red[covered].fill(Bit::kUnknown);
      const DecodeResult result = DecodeCells(reading);
      ASSERT_TRUE(result.key.has_value()) << key << " covered C" << covered;
      ASSERT_EQ(result.key->value(), key);
      ASSERT_EQ(result.bits_from_second_copy, 8);
      ASSERT_TRUE(result.bit_from_parity);
    }
  }
}

TEST(Cells, TwoMissingCodeBitsAreRefusedNotGuessed) {
  CellReading reading = ToReading(EncodeCells(TagKey(4242)));
  reading.red[0][1] = Bit::kUnknown;  // h1
  reading.red[1][2] = Bit::kUnknown;  // h2
  EXPECT_EQ(DecodeCells(reading).error, DecodeError::kTooManyUnknown);

  CellReading both_copies = ToReading(EncodeCells(TagKey(4242)));
  both_copies.green[0].fill(Bit::kUnknown);  // high byte, copy A
  both_copies.green[2].fill(Bit::kUnknown);  // high byte, copy B
  EXPECT_EQ(DecodeCells(both_copies).error, DecodeError::kTooManyUnknown);
}

TEST(Cells, MissingBitPlusAnErrorIsRejected) {
  for (int key = 0; key < kKeyCount; key += 7) {
    for (int missing = 16; missing < 20; ++missing) {
      for (int wrong = 0; wrong < 20; ++wrong) {
        if (wrong == missing) continue;
        CellReading reading = ToReading(EncodeCells(TagKey(key)));
        FlipCodeBit(reading, wrong);
        const int element = missing - 16;
        reading.red[element][(element + 1) % 4] = Bit::kUnknown;
        ASSERT_FALSE(DecodeCells(reading).key.has_value()) << key << " " << missing << " " << wrong;
      }
    }
  }
}

TEST(Cells, OrientationIsFoundForEveryRotationEvenWithOneElementCovered) {
  for (int key = 0; key < kKeyCount; key += 97) {
    const CellReading canonical = ToReading(EncodeCells(TagKey(key)));
    for (int r = 0; r < 4; ++r) {
      // A reading that starts at element (4 − r): rotating it by r brings C0 back to index 0.
      const CellReading seen = RotateReading(canonical, (4 - r) % 4);
      ASSERT_EQ(FindOrientation(seen), r) << key;
      EXPECT_EQ(DecodeCells(RotateReading(seen, r)).key, TagKey(key));
      for (int covered = 0; covered < 4; ++covered) {
        CellReading partial = seen;
        partial.green[covered].fill(Bit::kUnknown);
        partial.red[covered].fill(Bit::kUnknown);
        ASSERT_EQ(FindOrientation(partial), r) << key << " covered " << covered;
      }
    }
  }
}

TEST(Cells, RotationKeepsSectorsInTheirAngularPlace) {
  // Turning the reading frame by a quarter turn moves element e to e − 1 and every sector by two.
  CellReading reading;
  for (auto& element : reading.green) element.fill(Bit::kZero);
  for (auto& element : reading.red) element.fill(Bit::kZero);
  reading.green[1][2] = Bit::kOne;
  reading.red[1][1] = Bit::kOne;
  const CellReading rotated = RotateReading(reading, 1);
  EXPECT_EQ(rotated.green[0][0], Bit::kOne);
  EXPECT_EQ(rotated.red[0][0], Bit::kOne);
  EXPECT_EQ(RotateReading(rotated, 3).green[1][2], Bit::kOne);
}

TEST(Cells, AmbiguousOrThinOrientationIsRefused) {
  CellReading blank;
  for (auto& element : blank.red) element.fill(Bit::kUnknown);
  EXPECT_FALSE(FindOrientation(blank).has_value());
  CellReading all_ones = blank;
  for (auto& element : all_ones.red) element.fill(Bit::kOne);
  EXPECT_FALSE(FindOrientation(all_ones).has_value());
}

}  // namespace
}  // namespace pintag
