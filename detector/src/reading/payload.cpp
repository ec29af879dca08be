#include "reading/payload.hpp"

namespace pintag::stage {

PayloadResult DecodePayload(const CellReading& canonical) {
  PayloadResult result;
  const std::optional<int> turns = FindOrientation(canonical);
  if (!turns || *turns != 0) {
    result.error = "codec orientation check failed";
    return result;
  }
  const DecodeResult decoded = DecodeCells(canonical);
  if (!decoded.key) {
    result.error = std::string(ToString(decoded.error));
    return result;
  }
  result.key = decoded.key;
  result.bits_from_second_copy = decoded.bits_from_second_copy;
  result.bit_from_parity = decoded.bit_from_parity;
  return result;
}

}  // namespace pintag::stage
