#pragma once
// CLI11 checks that read option text with the parsers the HTTP routes use, so `pintag` and the
// API read a number or a size the same way and say the same about text that is not one. The
// ranges are each command's own: `pintag render` draws tags from 1 to 1000 mm at 50 to 4800 dpi,
// where the HTTP tag routes take 5 to 500 mm at 72 to 1200 dpi (docs/API.md).

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdlib>
#include <string>

#include "pintag/codec/tag_key.hpp"

namespace pintag::cli {

/// A number that is finite: CLI11's ranges compare with < and >, which NaN passes ("nan" would
/// reach a render as a size of nan mm, or turn the server's body limit off). Put it before them.
inline CLI::Validator FiniteNumber() {
  return {[](std::string& text) -> std::string {
            char* end = nullptr;
            const double value = std::strtod(text.c_str(), &end);
            if (end == text.c_str() || *end != '\0' || !std::isfinite(value)) {
              return "must be a finite number, got '" + text + "'";
            }
            return {};
          },
          "NUMBER"};
}

/// A tag key as ParseTagKey reads it (the routes' {key}): 0 to 32767.
inline CLI::Validator TagKeyCheck() {
  return {[](std::string& text) { return ParseTagKey(text).error; }, "KEY(0-32767)"};
}

}  // namespace pintag::cli
