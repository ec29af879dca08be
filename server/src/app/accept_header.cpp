#include "app/accept_header.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <string>

namespace pintag::app {
namespace {

std::string_view Trimmed(std::string_view text) {
  while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
  while (!text.empty() && (text.back() == ' ' || text.back() == '\t')) text.remove_suffix(1);
  return text;
}

std::string Lower(std::string_view text) {
  std::string lower(text);
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return lower;
}

/// The q parameter among a range's parameters ("q=0.5"), or 1 when it has none or one that does
/// not read as a weight.
double Weight(std::string_view parameters) {
  while (!parameters.empty()) {
    const std::size_t end = std::min(parameters.find(';'), parameters.size());
    const std::string_view parameter = Trimmed(parameters.substr(0, end));
    parameters.remove_prefix(std::min(end + 1, parameters.size()));
    if (parameter.size() < 2 || (parameter[0] != 'q' && parameter[0] != 'Q') ||
        parameter[1] != '=') {
      continue;
    }
    const std::string_view value = Trimmed(parameter.substr(2));
    double weight = 1;
    const auto [next, error] = std::from_chars(value.data(), value.data() + value.size(), weight);
    // "nan" reads as a number, and fails every comparison: asked as a range, not as its edges.
    if (error != std::errc() || next != value.data() + value.size() ||
        !(weight >= 0 && weight <= 1)) {
      return 1;
    }
    return weight;
  }
  return 1;
}

}  // namespace

double AcceptQuality(std::string_view accept, std::string_view media_type) {
  const std::size_t slash = media_type.find('/');
  const std::string_view type = media_type.substr(0, slash);
  // 0: no range names it; 1: "*/*"; 2: "type/*"; 3: the media type itself.
  int best_specificity = 0;
  double quality = 0;
  while (!accept.empty()) {
    const std::size_t end = std::min(accept.find(','), accept.size());
    const std::string_view element = accept.substr(0, end);
    accept.remove_prefix(std::min(end + 1, accept.size()));
    const std::size_t semicolon = std::min(element.find(';'), element.size());
    const std::string range = Lower(Trimmed(element.substr(0, semicolon)));
    int specificity = 0;
    if (range == media_type) {
      specificity = 3;
    } else if (range.size() == type.size() + 2 && range.starts_with(type) &&
               range.ends_with("/*")) {
      specificity = 2;
    } else if (range == "*/*") {
      specificity = 1;
    }
    if (specificity > best_specificity) {
      best_specificity = specificity;
      quality = Weight(element.substr(std::min(semicolon + 1, element.size())));
    }
  }
  return quality;
}

}  // namespace pintag::app
