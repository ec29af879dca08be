#pragma once
// Untrusted UTF-8 (names from the registry, bins from sort plans) made safe to draw.

#include <cstddef>
#include <string>
#include <string_view>

namespace pintag::label {

inline constexpr std::size_t kMaxDrawnCodePoints = 200;  // longer text is cut before measuring

/// Valid UTF-8 for any input: invalid or overlong sequences and surrogates become U+FFFD, control
/// and bidi-override characters are dropped, runs of white space become one space, ends are
/// trimmed, and the result is cut to kMaxDrawnCodePoints code points; `cut`, when given, says
/// whether it was (a bin cut short must not print, a name shows its cut).
std::string SanitizeUtf8(std::string_view text, bool* cut = nullptr);

}  // namespace pintag::label
