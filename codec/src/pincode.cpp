#include "pintag/codec/pincode.hpp"

#include "pintag/codec/utf8.hpp"

namespace pintag {
namespace {

/// Characters as a person counts them: "１１０００１" is six, though 18 bytes. A byte that is not
/// valid UTF-8 counts as one.
std::size_t CharacterCount(std::string_view text) {
  std::size_t count = 0;
  for (std::size_t i = 0; i < text.size(); ++count) {
    const Utf8CodePoint point = DecodeUtf8(text, i);
    i += point.length > 0 ? point.length : 1;
  }
  return count;
}

}  // namespace

ParsedPincode ParsePincode(std::string_view text) {
  const std::size_t characters = CharacterCount(text);
  if (characters != 6) {
    return {std::nullopt,
            "a pincode has exactly 6 digits, got " + std::to_string(characters) + " characters"};
  }
  std::uint32_t value = 0;
  for (const char c : text) {
    if (c < '0' || c > '9') {
      // Six characters in more than six bytes: digits of another script, or fullwidth ones.
      return {std::nullopt, text.size() == 6 ? "a pincode has only the digits 0-9"
                                             : "a pincode has only the digits 0-9 (ASCII); "
                                               "other scripts' digits are not read"};
    }
    value = value * 10 + static_cast<std::uint32_t>(c - '0');
  }
  if (text.front() == '0') return {std::nullopt, "a pincode cannot start with 0"};
  return {Pincode(value), {}};
}

}  // namespace pintag
