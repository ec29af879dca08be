#pragma once
// The shortened Hamming(20,15) code of format v1 (DESIGN.md §2): distance 3.

#include <array>
#include <cstdint>

namespace pintag {

inline constexpr int kParityBits = 5;

/// Position (1 … 31, never a power of two) of data bit i, i = 0 the least significant key bit.
inline constexpr std::array<std::uint8_t, 15> kDataBitPositions = {3,  5,  6,  7,  9,  10, 11, 12,
                                                                   13, 14, 15, 17, 18, 19, 20};

/// Parity bits of a 15-bit key: bit j of the result is h_j, the XOR of the data bits whose
/// position has bit j set.
constexpr std::uint8_t HammingParity(std::uint16_t key) {
  std::uint8_t parity = 0;
  for (int i = 0; i < 15; ++i) {
    if ((key >> i) & 1U) parity ^= kDataBitPositions[i];
  }
  return parity & 0x1F;
}

}  // namespace pintag
