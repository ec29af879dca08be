#include "pintag/codec/tag_key.hpp"

namespace pintag {

ParsedTagKey ParseTagKey(std::string_view text) {
  const std::string wanted = "a key is an integer from 0 to " + std::to_string(kKeyCount - 1);
  // Five digits at most: longer text cannot be a key and must not overflow the sum below.
  if (text.empty() || text.size() > 5) return {std::nullopt, wanted};
  int value = 0;
  for (const char c : text) {
    if (c < '0' || c > '9') return {std::nullopt, wanted};
    value = value * 10 + (c - '0');
  }
  if (!TagKey::IsValid(value)) return {std::nullopt, wanted};
  return {TagKey(static_cast<std::uint16_t>(value)), {}};
}

}  // namespace pintag
