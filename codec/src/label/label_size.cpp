#include "pintag/codec/label_size.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <utility>

#include "label/label_layout.hpp"

namespace pintag {
namespace {

constexpr std::size_t kMaxSizeText = 32;

struct Named {
  std::string_view name;
  LabelSize size;
};
constexpr std::array<Named, 1> kNamedSizes = {{{"a6", kLabelA6}}};

struct Unit {
  std::string_view suffix;
  double mm;
};
constexpr std::array<Unit, 3> kUnits = {{{"mm", 1.0}, {"cm", 10.0}, {"in", kMmPerInch}}};

std::string Format(double mm) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", mm);
  return text;
}

// The most characters one side's number may have ("49.999999999" and no more).
constexpr std::size_t kMaxSideText = 12;

// A plain decimal: digits with at most one point; no sign, exponent, "inf" or "nan".
std::optional<double> ParseNumber(std::string_view text) {
  if (text.empty()) return std::nullopt;  // the length is checked where the sides are split
  int points = 0;
  int digits = 0;
  for (char c : text) {
    if (c == '.') {
      ++points;
    } else if (c >= '0' && c <= '9') {
      ++digits;
    } else {
      return std::nullopt;
    }
  }
  if (points > 1 || digits == 0) return std::nullopt;
  double value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return value;
}

ParsedLabelSize Fail(std::string error) {
  return {std::nullopt, std::move(error)};
}

}  // namespace

std::string ValidateLabelSize(const LabelSize& size) {
  for (double side : {size.width_mm, size.height_mm}) {
    if (!std::isfinite(side) || side < kMinLabelSideMm - 1e-9 || side > kMaxLabelSideMm + 1e-9) {
      return "label sides must be " + Format(kMinLabelSideMm) + " to " + Format(kMaxLabelSideMm) +
             " mm, got " + Format(size.width_mm) + " x " + Format(size.height_mm) + " mm";
    }
  }
  const double aspect =
      std::max(size.width_mm, size.height_mm) / std::min(size.width_mm, size.height_mm);
  if (aspect > kMaxLabelAspect + 1e-9) {
    return "label aspect ratio must be at most " + Format(kMaxLabelAspect) + ":1, got " +
           Format(size.width_mm) + " x " + Format(size.height_mm) + " mm";
  }
  const double tag_side = label::ComputeLayout(size).placement.square_side_mm;
  if (tag_side < kMinLabelTagSideMm - 1e-9) {
    return "a " + Format(size.width_mm) + " x " + Format(size.height_mm) +
           " mm label leaves its tag " + Format(std::floor(tag_side * 10) / 10) +
           " mm across beside the text; labels must leave at least " + Format(kMinLabelTagSideMm) +
           " mm (e.g. 50x75mm, 75x75mm or 75x50mm)";
  }
  return {};
}

ParsedLabelSize ParseLabelSize(std::string_view text) {
  static constexpr std::string_view kExpected = "expected e.g. 100x150mm, a6 or 4x6in";
  if (text.size() > kMaxSizeText)
    return Fail("label size text is too long; " + std::string(kExpected));
  std::string s;
  for (char c : text) {
    if (c == ' ') continue;
    s += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  if (s.empty()) return Fail("empty label size; " + std::string(kExpected));
  for (const Named& named : kNamedSizes) {
    if (s == named.name) return {named.size, {}};
  }
  const Unit* unit = nullptr;
  for (const Unit& u : kUnits) {
    if (s.size() > u.suffix.size() && s.ends_with(u.suffix)) unit = &u;
  }
  const std::string shown(text);
  if (unit == nullptr) {
    return Fail("label size '" + shown + "' needs a unit (mm, cm or in) or a name (a6); " +
                std::string(kExpected));
  }
  const std::string_view body = std::string_view(s).substr(0, s.size() - unit->suffix.size());
  const std::size_t x = body.find('x');
  if (x == std::string_view::npos || body.find('x', x + 1) != std::string_view::npos) {
    return Fail("label size '" + shown + "' must be WIDTHxHEIGHT with a unit; " +
                std::string(kExpected));
  }
  if (x > kMaxSideText || body.size() - x - 1 > kMaxSideText) {
    return Fail("label size '" + shown + "' has a side of more than " +
                std::to_string(kMaxSideText) + " characters; " + std::string(kExpected));
  }
  const std::optional<double> width = ParseNumber(body.substr(0, x));
  const std::optional<double> height = ParseNumber(body.substr(x + 1));
  if (!width || !height) {
    return Fail("label size '" + shown + "' has a side that is not a plain positive number; " +
                std::string(kExpected));
  }
  // To a nanometre, so "4x6in" is exactly kLabel4x6In despite binary rounding.
  const auto mm = [&](double value) { return std::round(value * unit->mm * 1e6) / 1e6; };
  const LabelSize size{mm(*width), mm(*height)};
  std::string error = ValidateLabelSize(size);
  if (!error.empty()) return Fail(std::move(error));
  return {size, {}};
}

std::string ToString(const LabelSize& size) {
  return Format(size.width_mm) + "x" + Format(size.height_mm) + "mm";
}

}  // namespace pintag
