#include "pintag/codec/pincode.hpp"

namespace pintag {

ParsedPincode ParsePincode(std::string_view text) {
  if (text.size() != 6) {
    return {std::nullopt,
            "a pincode has exactly 6 digits, got " + std::to_string(text.size()) + " characters"};
  }
  std::uint32_t value = 0;
  for (const char c : text) {
    if (c < '0' || c > '9') return {std::nullopt, "a pincode has only the digits 0-9"};
    value = value * 10 + static_cast<std::uint32_t>(c - '0');
  }
  if (text.front() == '0') return {std::nullopt, "a pincode cannot start with 0"};
  return {Pincode(value), {}};
}

}  // namespace pintag
