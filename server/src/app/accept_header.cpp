#include "app/accept_header.hpp"

#include <algorithm>
#include <charconv>
#include <string>

#include "pintag/server/header_text.hpp"

namespace pintag::app {
namespace {

using server::MediaType;
using server::Trim;

/// The q parameter among a range's parameters ("q=0.5"), or 1 when it has none or one that does
/// not read as a weight.
double Weight(std::string_view parameters) {
  while (!parameters.empty()) {
    const std::size_t end = std::min(parameters.find(';'), parameters.size());
    const std::string_view parameter = Trim(parameters.substr(0, end));
    parameters.remove_prefix(std::min(end + 1, parameters.size()));
    if (parameter.size() < 2 || (parameter[0] != 'q' && parameter[0] != 'Q') ||
        parameter[1] != '=') {
      continue;
    }
    const std::string_view value = Trim(parameter.substr(2));
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
    const std::string range = MediaType(element);
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
