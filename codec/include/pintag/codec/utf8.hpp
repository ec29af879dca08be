#pragma once
// UTF-8, decoded strictly: the one decoder behind the registry's text checks (pintag::db) and the
// label's text sanitizing (pintag::label). Overlong forms, UTF-16 surrogates, code points beyond
// U+10FFFF, stray continuation bytes and truncated sequences are all invalid.

#include <cstddef>
#include <string>
#include <string_view>

namespace pintag {

/// One code point read from UTF-8 text.
struct Utf8CodePoint {
  char32_t value = 0;      ///< the code point; meaningful only when `length` > 0
  std::size_t length = 0;  ///< its bytes, 1 to 4; 0 when the bytes there are not valid UTF-8
};

/// The code point that starts at byte `offset` of `text`. Precondition: offset < text.size().
Utf8CodePoint DecodeUtf8(std::string_view text, std::size_t offset);

/// Characters as a person counts them (code points): "１１０００１" is six, though 18 bytes. A
/// byte that is not valid UTF-8 counts as one.
std::size_t Utf8CharacterCount(std::string_view text);

/// A code point as a message names it: "U+00E9", "U+1F600".
std::string CodePointName(char32_t code_point);

/// `text` quoted for a message, 'like this', cut after at most `max_bytes` at a character's
/// start (never inside one), with an ellipsis before the closing quote when it was cut.
std::string QuotedPrefix(std::string_view text, std::size_t max_bytes);

/// Appends `code_point` as UTF-8. Precondition: a Unicode scalar value (at most U+10FFFF, not a
/// surrogate), e.g. one DecodeUtf8 returned.
void AppendUtf8(std::string& out, char32_t code_point);

}  // namespace pintag
