#pragma once
// CLI11 checks that read option text with the parsers the HTTP routes use, so `pintag` and the
// API read a number or a size the same way and say the same about text that is not one. The
// ranges are each command's own: `pintag render` draws tags from 1 to 1000 mm at 50 to 4800 dpi,
// where the HTTP tag routes take 5 to 500 mm at 72 to 1200 dpi (docs/API.md).

#include <CLI/CLI.hpp>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <sstream>
#include <string>
#include <system_error>

#include "pintag/codec/tag_key.hpp"

namespace pintag::cli {

/// The whole text as a decimal number, as the HTTP routes read one (std::from_chars): no sign
/// before it but a minus, no spaces, no hexadecimal. strtod took " 10" and "0x10" (a 16 mm tag).
inline std::optional<double> DecimalNumber(const std::string& text) {
  double value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return value;
}

/// A number that is finite: CLI11's ranges compare with < and >, which NaN passes ("nan" would
/// reach a render as a size of nan mm, or turn the server's body limit off). Put it before them.
inline CLI::Validator FiniteNumber() {
  return {[](std::string& text) -> std::string {
            const std::optional<double> value = DecimalNumber(text);
            if (!value || !std::isfinite(*value)) {
              return "must be a finite number, got '" + text + "'";
            }
            return {};
          },
          "NUMBER"};
}

/// A finite number from `min` to `max`, refused in the routes' words ("must be a number from
/// 0.001 to 1e+07"): CLI::Range printed an unbounded side as DBL_MAX's 309 digits.
inline CLI::Validator NumberFromTo(double min, double max) {
  const auto shown = [](double v) {
    std::ostringstream out;
    out << v;
    return out.str();
  };
  const std::string range = shown(min) + " to " + shown(max);
  return {[min, max, range](std::string& text) -> std::string {
            const std::optional<double> value = DecimalNumber(text);
            if (!value || !std::isfinite(*value) || *value < min || *value > max) {
              return "must be a number from " + range + ", got '" + text + "'";
            }
            return {};
          },
          "NUMBER"};
}

/// Integer text read as decimal, as the HTTP routes read it. CLI11 2.1 converts with strtoll's
/// base 0, so `--key 010` was key 8 and `--port 0x1f90` port 8080: a label for another key. This
/// transform refuses what is not decimal digits (after an optional minus) and drops leading
/// zeros; AddRegisteredCommands puts it first on every integer option but those that read their
/// text themselves (a transform named kReadsItsText, such as TagKeyText).
inline CLI::Validator DecimalInteger() {
  return {[](std::string& text) -> std::string {
            const std::size_t sign = !text.empty() && text.front() == '-' ? 1 : 0;
            const std::size_t digits = text.find_first_not_of("0123456789", sign);
            if (text.size() == sign || digits != std::string::npos) {
              return "must be a whole number in decimal digits, got '" + text + "'";
            }
            const std::size_t first = std::min(text.find_first_not_of('0', sign), text.size() - 1);
            text.erase(sign, first - sign);
            // CLI11 takes strtoll's answer without its range error: 99999999999999999999 was
            // read as 9223372036854775807. No option takes a number of 19 digits.
            if (text.size() - sign > 18) return "is too large: '" + text + "'";
            return {};
          },
          ""};
}

/// The name of a transform that reads an integer option's text whole, in decimal, and leaves it
/// as its number's plain decimal digits.
inline constexpr const char* kReadsItsText = "reads-its-text";

/// A tag key as ParseTagKey reads it (the routes' {key}): 0 to 32767, refused in the route's
/// words. Put on with transform(): it leaves the key's plain digits for CLI11 to convert.
inline CLI::Validator TagKeyText() {
  CLI::Validator validator(
      [](std::string& text) -> std::string {
        const ParsedTagKey parsed = ParseTagKey(text);
        if (parsed) text = std::to_string(parsed.key->value());
        return parsed.error;
      },
      "KEY(0-32767)");
  validator.name(kReadsItsText);
  return validator;
}

}  // namespace pintag::cli
