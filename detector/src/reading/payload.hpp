#pragma once
// Stage 6b, payload and parity: hands the reading to the codec, which alone decides. The reading
// must already be canonical; the codec's own orientation check must agree.

#include <optional>
#include <string>

#include "pintag/codec/cells.hpp"

namespace pintag::stage {

struct PayloadResult {
  std::optional<TagKey> key;
  std::string error;  ///< why no key
  int bits_from_second_copy = 0;
  bool bit_from_parity = false;
};

PayloadResult DecodePayload(const CellReading& canonical);

}  // namespace pintag::stage
