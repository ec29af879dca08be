#include "pintag/codec/cells.hpp"

#include "pintag/codec/hamming.hpp"

namespace pintag {
namespace {

constexpr int kPayloadBits = 16;

// Payload bit b (15 = most significant) of copy A lives on C0 (high byte) or C1 (low byte); copy B
// on C2 and C3. Within an element the byte's most significant bit is in sector 0.
struct SectorRef {
  int element;
  int sector;
};

constexpr SectorRef PayloadSector(int copy, int bit) {
  const int high_element = copy == 0 ? 0 : 2;
  return bit >= 8 ? SectorRef{high_element, 15 - bit} : SectorRef{high_element + 1, 7 - bit};
}

constexpr bool OrientationBit(int element) {
  return element != 0;
}

Bit ToBit(bool value) {
  return value ? Bit::kOne : Bit::kZero;
}

}  // namespace

TagCells EncodeCells(TagKey key) {
  const std::uint8_t parity = HammingParity(key.value());
  const std::uint16_t payload = static_cast<std::uint16_t>((key.value() << 1) | (parity & 1U));
  TagCells cells;
  for (int copy = 0; copy < 2; ++copy) {
    for (int bit = 0; bit < kPayloadBits; ++bit) {
      const SectorRef ref = PayloadSector(copy, bit);
      cells.green[ref.element][ref.sector] = ((payload >> bit) & 1U) != 0;
    }
  }
  for (int e = 0; e < kElements; ++e) {
    for (int q = 0; q < kRedQuadrants; ++q) cells.red[e][q] = OrientationBit(e);
    cells.red[e][InnerQuadrant(e)] = ((parity >> (e + 1)) & 1U) != 0;
  }
  return cells;
}

CellReading RotateReading(const CellReading& reading, int quarter_turns) {
  const int r = ((quarter_turns % 4) + 4) % 4;
  CellReading rotated;
  for (int e = 0; e < kElements; ++e) {
    const int from = (e + r) % kElements;
    for (int s = 0; s < kGreenSectors; ++s) {
      rotated.green[e][s] = reading.green[from][(s + 2 * r) % kGreenSectors];
    }
    for (int q = 0; q < kRedQuadrants; ++q) {
      rotated.red[e][q] = reading.red[from][(q + r) % kRedQuadrants];
    }
  }
  return rotated;
}

std::optional<int> FindOrientation(const CellReading& reading, int min_known_bits) {
  std::optional<int> found;
  for (int r = 0; r < 4; ++r) {
    const CellReading candidate = RotateReading(reading, r);
    int known = 0;
    bool contradicted = false;
    for (int e = 0; e < kElements; ++e) {
      for (int q = 0; q < kRedQuadrants; ++q) {
        if (q == InnerQuadrant(e)) continue;
        const Bit bit = candidate.red[e][q];
        if (bit == Bit::kUnknown) continue;
        ++known;
        contradicted |= bit != ToBit(OrientationBit(e));
      }
    }
    if (contradicted || known < min_known_bits) continue;
    if (found) return std::nullopt;  // two orientations fit: refuse rather than pick one
    found = r;
  }
  return found;
}

std::string_view ToString(DecodeError error) {
  switch (error) {
    case DecodeError::kNone:
      return "none";
    case DecodeError::kOrientation:
      return "orientation bits contradict the format";
    case DecodeError::kCopiesDisagree:
      return "the two payload copies disagree";
    case DecodeError::kTooManyUnknown:
      return "more than one code bit unreadable";
    case DecodeError::kParity:
      return "parity check failed";
  }
  return "unknown";
}

DecodeResult DecodeCells(const CellReading& reading) {
  DecodeResult result;
  for (int e = 0; e < kElements; ++e) {
    for (int q = 0; q < kRedQuadrants; ++q) {
      const Bit bit = reading.red[e][q];
      if (q != InnerQuadrant(e) && bit != Bit::kUnknown && bit != ToBit(OrientationBit(e))) {
        result.error = DecodeError::kOrientation;
        return result;
      }
    }
  }

  // The 20 code bits: data bits 0 … 14 at index 0 … 14, parity h0 … h4 at index 15 … 19.
  std::array<Bit, 20> code{};
  for (int bit = 0; bit < kPayloadBits; ++bit) {
    const SectorRef a = PayloadSector(0, bit);
    const SectorRef b = PayloadSector(1, bit);
    const Bit first = reading.green[a.element][a.sector];
    const Bit second = reading.green[b.element][b.sector];
    Bit merged = first;
    if (first != Bit::kUnknown && second != Bit::kUnknown && first != second) {
      result.error = DecodeError::kCopiesDisagree;
      return result;
    }
    if (first == Bit::kUnknown && second != Bit::kUnknown) {
      merged = second;
      ++result.bits_from_second_copy;
    } else if (second == Bit::kUnknown && first != Bit::kUnknown) {
      ++result.bits_from_second_copy;
    }
    // Payload bit 0 is h0, bits 1 … 15 are key bits 0 … 14.
    code[bit == 0 ? 15 : bit - 1] = merged;
  }
  for (int e = 0; e < kElements; ++e) code[16 + e] = reading.red[e][InnerQuadrant(e)];

  int unknown_index = -1;
  for (int i = 0; i < 20; ++i) {
    if (code[i] != Bit::kUnknown) continue;
    if (unknown_index >= 0) {
      result.error = DecodeError::kTooManyUnknown;
      return result;
    }
    unknown_index = i;
  }

  // The syndrome of a code word is zero. With one bit missing, try both values: exactly one can
  // give syndrome zero because every code position is non-zero, so this solves rather than guesses,
  // and the remaining parity equations still check every read bit.
  const auto syndrome = [&code](int missing_value) {
    std::uint16_t key = 0;
    std::uint8_t parity = 0;
    for (int i = 0; i < 15; ++i) {
      const bool one = code[i] == Bit::kUnknown ? missing_value != 0 : code[i] == Bit::kOne;
      if (one) key |= static_cast<std::uint16_t>(1U << i);
    }
    for (int j = 0; j < kParityBits; ++j) {
      const bool one =
          code[15 + j] == Bit::kUnknown ? missing_value != 0 : code[15 + j] == Bit::kOne;
      if (one) parity |= static_cast<std::uint8_t>(1U << j);
    }
    return std::pair{key, static_cast<std::uint8_t>(HammingParity(key) ^ parity)};
  };

  for (int value = 0; value < (unknown_index >= 0 ? 2 : 1); ++value) {
    const auto [key, bad] = syndrome(value);
    if (bad == 0) {
      result.key = TagKey(key);
      result.bit_from_parity = unknown_index >= 0;
      return result;
    }
  }
  result.error = DecodeError::kParity;
  return result;
}

}  // namespace pintag
