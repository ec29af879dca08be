#include "pintag/db/text.hpp"

#include <string>

#include "pintag/codec/utf8.hpp"

namespace pintag::db {

std::string_view TrimSpaces(std::string_view text) {
  const std::size_t first = text.find_first_not_of(' ');
  if (first == std::string_view::npos) return {};
  return text.substr(first, text.find_last_not_of(' ') - first + 1);
}

std::optional<Error> CheckText(std::string_view field, std::string_view value,
                               std::size_t max_bytes, bool allow_empty) {
  const auto invalid = [&](const std::string& why) {
    return Error{ErrorCode::kInvalid, std::string(field) + " " + why};
  };
  if (value.empty() && !allow_empty) return invalid("is empty");
  if (!allow_empty && value.find_first_not_of(' ') == std::string_view::npos) {
    return invalid("is only spaces");
  }
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
    const std::size_t length = DecodeUtf8(value, i).length;
    if (length == 0) return invalid("is not valid UTF-8 at byte " + std::to_string(i));
    i += length;
  }
  return std::nullopt;
}

}  // namespace pintag::db
