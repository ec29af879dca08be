#pragma once
// Key <-> the 48 cells of a format-v1 tag (DESIGN.md §2), and the rules for accepting a reading.
//
// Element e (0 … 3) is C0 top-left, C1 top-right, C2 bottom-right, C3 bottom-left. Its green ring
// has 8 sectors (sector s spans 45s° … 45s+45°, clockwise from up), its red disk 4 quadrants
// (quadrant q spans 90q° … 90q+90°). The decoder sees only bits; finding them is the detector's
// job.

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

#include "pintag/codec/tag_key.hpp"

namespace pintag {

inline constexpr int kElements = 4;
inline constexpr int kGreenSectors = 8;
inline constexpr int kRedQuadrants = 4;

/// The red quadrant of element e that faces the tag centre; it carries parity bit h_{e+1}.
constexpr int InnerQuadrant(int element) {
  return (element + 1) % kRedQuadrants;
}

template <typename T>
struct BasicCells {
  std::array<std::array<T, kGreenSectors>, kElements> green{};
  std::array<std::array<T, kRedQuadrants>, kElements> red{};
};

/// What a tag carries: true = bit 1 (high b*: yellow-green or orange-red), false = bit 0.
using TagCells = BasicCells<bool>;

/// One read cell: a bit, or unknown when the detector could not read it with confidence.
enum class Bit : std::uint8_t { kZero, kOne, kUnknown };

/// What a detector read from a tag, in some assumed corner order.
using CellReading = BasicCells<Bit>;

TagCells EncodeCells(TagKey key);

/// The reading as it would be if the element the detector took for C[r] were C0: reading elements
/// and angles are shifted by r quarter turns. Used to try the four possible orientations.
CellReading RotateReading(const CellReading& reading, int quarter_turns);

/// Quarter turns r for which RotateReading(reading, r) has no known orientation bit contradicting
/// format v1 (outer red quadrants 0 on C0, 1 elsewhere). Accepts only when exactly one r fits and
/// at least `min_known_bits` of the 12 orientation bits were read.
std::optional<int> FindOrientation(const CellReading& reading, int min_known_bits = 6);

enum class DecodeError : std::uint8_t {
  kNone,
  kOrientation,     ///< an orientation bit contradicts the format
  kCopiesDisagree,  ///< the two payload copies were both read and differ in some bit
  kTooManyUnknown,  ///< more than one of the 20 code bits is unreadable in both copies
  kParity,          ///< the code word fails the Hamming check
};

std::string_view ToString(DecodeError error);

struct DecodeResult {
  std::optional<TagKey> key;  ///< set only when the reading is fully consistent
  DecodeError error = DecodeError::kNone;
  int bits_from_second_copy = 0;  ///< payload bits unreadable in one copy, taken from the other
  bool bit_from_parity = false;   ///< one code bit unreadable in both copies, solved from parity
};

/// Decodes a reading already in canonical orientation (C0 is element 0). Never guesses: every read
/// bit must agree with the accepted key; at most one of the 20 code bits may be missing.
DecodeResult DecodeCells(const CellReading& reading);

}  // namespace pintag
