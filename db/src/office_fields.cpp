#include "pintag/db/office_fields.hpp"

#include <cctype>

namespace pintag::db {

bool MeansUnknown(std::string_view field) {
  std::string lower;
  for (const char c : field)
    lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return lower.empty() || lower == "na" || lower == "n/a" || lower == "null";
}

std::optional<std::string> NormalizedOfficeType(std::optional<std::string> type) {
  if (!type) return type;
  std::string letters;
  for (const char c : *type) {  // " H.O " too: an API client's value is not trimmed first
    if (c != '.' && c != ' ')
      letters += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  }
  if (letters.size() == 2 && letters[1] == 'O' &&
      std::isalpha(static_cast<unsigned char>(letters[0])) != 0) {
    return letters;
  }
  return type;
}

}  // namespace pintag::db
