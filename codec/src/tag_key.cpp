#include "pintag/codec/tag_key.hpp"

namespace pintag {

ParsedTagKey ParseTagKey(std::string_view text) {
  const std::string wanted = "a key is an integer from 0 to " + std::to_string(kKeyCount - 1);
  if (text.empty()) return {std::nullopt, wanted};
  // Leading zeros do not change the number ("000001" is key 1, as "00001" was); past them, five
  // digits at most: longer text cannot be a key and must not overflow the sum below.
  while (text.size() > 1 && text.front() == '0') text.remove_prefix(1);
  if (text.size() > 5) return {std::nullopt, wanted};
  int value = 0;
  for (const char c : text) {
    if (c < '0' || c > '9') return {std::nullopt, wanted};
    value = value * 10 + (c - '0');
  }
  if (!TagKey::IsValid(value)) return {std::nullopt, wanted};
  return {TagKey(static_cast<std::uint16_t>(value)), {}};
}

}  // namespace pintag
