#include "pintag/db/text.hpp"

#include <string>

namespace pintag::db {
namespace {

/// Length of the valid UTF-8 sequence at `text[i]`, or 0 when it is not one.
std::size_t Utf8Length(std::string_view text, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char lead = byte(i);
  if (lead < 0x80) return 1;
  std::size_t length = 0;
  std::uint32_t code = 0;
  if ((lead & 0xE0) == 0xC0) {
    length = 2;
    code = lead & 0x1F;
  } else if ((lead & 0xF0) == 0xE0) {
    length = 3;
    code = lead & 0x0F;
  } else if ((lead & 0xF8) == 0xF0) {
    length = 4;
    code = lead & 0x07;
  } else {
    return 0;
  }
  if (i + length > text.size()) return 0;
  for (std::size_t k = 1; k < length; ++k) {
    if ((byte(i + k) & 0xC0) != 0x80) return 0;
    code = (code << 6) | (byte(i + k) & 0x3F);
  }
  constexpr std::uint32_t kMinimum[] = {0, 0, 0x80, 0x800, 0x10000};
  if (code < kMinimum[length] || code > 0x10FFFF || (code >= 0xD800 && code <= 0xDFFF)) return 0;
  return length;
}

}  // namespace

std::optional<Error> CheckText(std::string_view field, std::string_view value,
                               std::size_t max_bytes, bool allow_empty) {
  const auto invalid = [&](const std::string& why) {
    return Error{ErrorCode::kInvalid, std::string(field) + " " + why};
  };
  if (value.empty() && !allow_empty) return invalid("is empty");
  if (value.size() > max_bytes) {
    return invalid("is " + std::to_string(value.size()) + " bytes long; at most " +
                   std::to_string(max_bytes) + " allowed");
  }
  for (std::size_t i = 0; i < value.size();) {
    const unsigned char c = static_cast<unsigned char>(value[i]);
    if (c < 0x20 || c == 0x7F) {
      return invalid("contains control character " + std::to_string(c) + " at byte " +
                     std::to_string(i));
    }
    const std::size_t length = Utf8Length(value, i);
    if (length == 0) return invalid("is not valid UTF-8 at byte " + std::to_string(i));
    i += length;
  }
  return std::nullopt;
}

}  // namespace pintag::db
