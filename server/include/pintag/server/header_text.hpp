#pragma once
// Header values as HTTP compares them: names and media types case-insensitively, around optional
// whitespace. Shared by admission (api.cpp), the cpp-httplib adapter (http_server.cpp) and the
// application's content negotiation (app/accept_header.cpp).

#include <algorithm>
#include <cctype>
#include <string>
#include <string_view>

namespace pintag::server {

/// ASCII lower case.
inline std::string Lower(std::string_view text) {
  std::string out(text);
  std::transform(out.begin(), out.end(), out.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

/// Without spaces and tabs at either end.
inline std::string_view Trim(std::string_view text) {
  while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
  while (!text.empty() && (text.back() == ' ' || text.back() == '\t')) text.remove_suffix(1);
  return text;
}

/// "image/PNG; q=1" -> "image/png".
inline std::string MediaType(std::string_view content_type) {
  return Lower(Trim(content_type.substr(0, content_type.find(';'))));
}

}  // namespace pintag::server
