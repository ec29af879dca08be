#pragma once
// CLI11 checks that read option text with the parsers the HTTP routes use, so `pintag` and the
// API accept the same values and say the same about the rest.

#include <CLI/CLI.hpp>
#include <string>

#include "pintag/codec/tag_key.hpp"

namespace pintag::cli {

/// A tag key as ParseTagKey reads it (the routes' {key}): 0 to 32767.
inline CLI::Validator TagKeyCheck() {
  return {[](std::string& text) { return ParseTagKey(text).error; }, "KEY(0-32767)"};
}

}  // namespace pintag::cli
