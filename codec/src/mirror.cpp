#include "pintag/codec/mirror.hpp"

namespace pintag {
namespace {

// Element e's place mirrored left to right: C0 (top-left) <-> C1 (top-right), C2 <-> C3.
constexpr int MirroredElement(int e) {
  return e ^ 1;
}

CellReading AsReading(const TagCells& cells) {
  CellReading reading;
  for (int e = 0; e < kElements; ++e) {
    for (int s = 0; s < kGreenSectors; ++s) {
      reading.green[e][s] = cells.green[e][s] ? Bit::kOne : Bit::kZero;
    }
    for (int q = 0; q < kRedQuadrants; ++q) {
      reading.red[e][q] = cells.red[e][q] ? Bit::kOne : Bit::kZero;
    }
  }
  return reading;
}

}  // namespace

TagCells MirrorCells(const TagCells& cells) {
  TagCells mirrored;
  for (int e = 0; e < kElements; ++e) {
    const int from = MirroredElement(e);
    for (int s = 0; s < kGreenSectors; ++s) {
      mirrored.green[e][s] = cells.green[from][kGreenSectors - 1 - s];
    }
    for (int q = 0; q < kRedQuadrants; ++q) {
      mirrored.red[e][q] = cells.red[from][kRedQuadrants - 1 - q];
    }
  }
  return mirrored;
}

std::optional<TagKey> MirrorImageKey(TagKey key) {
  // Read the mirrored tag as a detector would: find C0 by the orientation quadrants, turn, decode.
  const CellReading reading = AsReading(MirrorCells(EncodeCells(key)));
  const std::optional<int> turns = FindOrientation(reading, /*min_known_bits=*/12);
  if (!turns) return std::nullopt;
  return DecodeCells(RotateReading(reading, *turns)).key;
}

}  // namespace pintag
