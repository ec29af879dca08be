#include "pintag/codec/pincode.hpp"

#include "pintag/codec/utf8.hpp"

namespace pintag {
namespace {

/// The scripts a pincode is likely typed in by mistake: the digit blocks of India's scripts,
/// Arabic-Indic ones and fullwidth ones (an East Asian keyboard). Each block is ten code points.
bool IsDigitOfAnotherScript(char32_t point) {
  static constexpr char32_t kZeros[] = {0x0660, 0x06F0, 0x0966, 0x09E6, 0x0A66, 0x0AE6,
                                        0x0B66, 0x0BE6, 0x0C66, 0x0CE6, 0x0D66, 0xFF10};
  for (const char32_t zero : kZeros) {
    if (point >= zero && point <= zero + 9) return true;
  }
  return false;
}

bool HasDigitOfAnotherScript(std::string_view text) {
  for (std::size_t i = 0; i < text.size();) {
    const Utf8CodePoint point = DecodeUtf8(text, i);
    if (point.length > 0 && IsDigitOfAnotherScript(point.value)) return true;
    i += point.length > 0 ? point.length : 1;
  }
  return false;
}

}  // namespace

ParsedPincode ParsePincode(std::string_view text) {
  const std::size_t characters = Utf8CharacterCount(text);
  if (characters != 6) {
    return {std::nullopt,
            "a pincode has exactly 6 digits, got " + std::to_string(characters) + " characters"};
  }
  std::uint32_t value = 0;
  for (const char c : text) {
    if (c < '0' || c > '9') {
      return {std::nullopt, HasDigitOfAnotherScript(text)
                                ? "a pincode has only the digits 0-9 (ASCII); other scripts' "
                                  "digits are not read"
                                : "a pincode has only the digits 0-9"};
    }
    value = value * 10 + static_cast<std::uint32_t>(c - '0');
  }
  if (text.front() == '0') return {std::nullopt, "a pincode cannot start with 0"};
  return {Pincode(value), {}};
}

}  // namespace pintag
