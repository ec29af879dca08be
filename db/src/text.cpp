#include "pintag/db/text.hpp"

#include <glib.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>

#include "pintag/codec/utf8.hpp"

namespace pintag::db {

std::string_view TrimSpaces(std::string_view text) {
  const std::size_t first = text.find_first_not_of(' ');
  if (first == std::string_view::npos) return {};
  return text.substr(first, text.find_last_not_of(' ') - first + 1);
}

namespace {

// Unicode 15: the space separators (Zs), U+2028/U+2029 (Zl, Zp), U+0085, the format characters
// (Cf) and the other characters that render as nothing on their own.
bool IsInvisible(char32_t c) {
  struct Range {
    char32_t first, last;
  };
  static constexpr Range kInvisible[] = {
      {0x0020, 0x0020},   {0x0085, 0x0085},   {0x00A0, 0x00A0},   {0x00AD, 0x00AD},
      {0x034F, 0x034F},   {0x0600, 0x0605},   {0x061C, 0x061C},   {0x06DD, 0x06DD},
      {0x070F, 0x070F},   {0x0890, 0x0891},   {0x08E2, 0x08E2},   {0x115F, 0x1160},
      {0x1680, 0x1680},   {0x180B, 0x180F},   {0x2000, 0x200F},   {0x2028, 0x202F},
      {0x205F, 0x2064},   {0x2066, 0x206F},   {0x3000, 0x3000},   {0x3164, 0x3164},
      {0xFE00, 0xFE0F},   {0xFEFF, 0xFEFF},   {0xFFA0, 0xFFA0},   {0xFFF9, 0xFFFB},
      {0x110BD, 0x110BD}, {0x110CD, 0x110CD}, {0x13430, 0x1343F}, {0x1BCA0, 0x1BCA3},
      {0x1D173, 0x1D17A}, {0xE0001, 0xE0001}, {0xE0020, 0xE007F}, {0xE0100, 0xE01EF},
  };
  for (const Range& range : kInvisible) {
    if (c < range.first) return false;  // ranges ascend
    if (c <= range.last) return true;
  }
  return false;
}

/// What TrimUnicodeSpaces drops: the tab (CheckText refuses it inside text) and the characters
/// that stand for a space, each of them also invisible to IsBlank.
bool IsTrimmedSpace(char32_t c) {
  return c == U'\t' || c == U' ' || c == 0x00A0 || c == 0x1680 || (c >= 0x2000 && c <= 0x200B) ||
         c == 0x202F || c == 0x205F || c == 0x2060 || c == 0x3000 || c == 0xFEFF;
}

}  // namespace

const char* RefusedCodePoint(char32_t c) {
  if (c >= 0x80 && c <= 0x9F) return "control character";
  if (c == 0x2028 || c == 0x2029) return "line or paragraph separator";
  if ((c >= 0x202A && c <= 0x202E) || (c >= 0x2066 && c <= 0x2069)) {
    return "bidi embedding, override or isolate";
  }
  return nullptr;
}

std::string_view TrimUnicodeSpaces(std::string_view text) {
  while (!text.empty()) {
    const Utf8CodePoint first = DecodeUtf8(text, 0);
    if (first.length == 0 || !IsTrimmedSpace(first.value)) break;
    text.remove_prefix(first.length);
  }
  while (!text.empty()) {
    // The last code point starts at the last byte that is not a continuation byte (10xxxxxx).
    std::size_t start = text.size() - 1;
    while (start > 0 && text.size() - start < 4 &&
           (static_cast<unsigned char>(text[start]) & 0xC0) == 0x80) {
      --start;
    }
    const Utf8CodePoint last = DecodeUtf8(text, start);
    if (last.length != text.size() - start || !IsTrimmedSpace(last.value)) break;
    text.remove_suffix(last.length);
  }
  return text;
}

bool IsBlank(std::string_view text) {
  for (std::size_t i = 0; i < text.size();) {
    const Utf8CodePoint decoded = DecodeUtf8(text, i);
    if (decoded.length == 0 || !IsInvisible(decoded.value)) return false;
    i += decoded.length;
  }
  return true;
}

namespace {

std::optional<Error> CheckTextAs(std::string_view field, std::string_view value,
                                 std::size_t max_bytes, bool allow_empty, bool stored) {
  const auto invalid = [&](const std::string& why) {
    return Error{ErrorCode::kInvalid, std::string(field) + " " + why};
  };
  if (value.empty() && !allow_empty) return invalid("is empty");
  // "\u200b" or a no-break space would be stored as a name nobody can see or type.
  if (!allow_empty && IsBlank(value))
    return invalid("is blank (only spaces or invisible characters)");
  if (value.size() > max_bytes) {
    // Said in characters too: a clerk counts letters, and a letter of an Indian script is three
    // bytes, so "200 bytes" is about 66 of them.
    return invalid("is " + std::to_string(value.size()) + " bytes long in UTF-8 (" +
                   std::to_string(Utf8CharacterCount(value)) + " characters); at most " +
                   std::to_string(max_bytes) +
                   " bytes are allowed, where a letter of an Indian script takes 3");
  }
  for (std::size_t i = 0; i < value.size();) {
    const unsigned char c = static_cast<unsigned char>(value[i]);
    if (c < 0x20 || c == 0x7F) {
      return invalid("contains control character " + std::to_string(c) + " at byte " +
                     std::to_string(i));
    }
    const Utf8CodePoint decoded = DecodeUtf8(value, i);
    if (decoded.length == 0) return invalid("is not valid UTF-8 at byte " + std::to_string(i));
    if (const char* what = stored ? RefusedCodePoint(decoded.value) : nullptr) {
      return invalid("contains " + std::string(what) + " " + CodePointName(decoded.value) +
                     " at byte " + std::to_string(i));
    }
    i += decoded.length;
  }
  return std::nullopt;
}

}  // namespace

std::optional<Error> CheckText(std::string_view field, std::string_view value,
                               std::size_t max_bytes, bool allow_empty) {
  return CheckTextAs(field, value, max_bytes, allow_empty, true);
}

std::optional<Error> CheckQueryText(std::string_view field, std::string_view value,
                                    std::size_t max_bytes) {
  return CheckTextAs(field, value, max_bytes, true, false);
}

std::optional<Error> CheckShownName(std::string_view field, std::string_view value,
                                    std::size_t max_bytes) {
  if (auto error = CheckText(field, value, max_bytes)) return error;
  for (std::size_t i = 0; i < value.size();) {
    const Utf8CodePoint decoded = DecodeUtf8(value, i);
    const bool at_start = i == 0;
    const bool at_an_end = at_start || i + decoded.length == value.size();
    // A joiner may end a word (Malayalam's older chillu forms end in U+200D), not start one.
    const bool joiner = decoded.value == 0x200C || decoded.value == 0x200D;
    const bool kept = joiner ? !at_start : decoded.value == U' ' && !at_an_end;
    if (IsInvisible(decoded.value) && !kept) {
      const std::string code = CodePointName(decoded.value);
      return Error{ErrorCode::kInvalid,
                   std::string(field) + " '" + std::string(value.substr(0, 64)) + "' " +
                       (at_an_end ? "starts or ends with a space or an invisible character ("
                                  : "holds an invisible character (") +
                       code + " at byte " + std::to_string(i) +
                       "): it would read like another name"};
    }
    i += decoded.length;
  }
  return std::nullopt;
}

std::string CanonicalForm(std::string_view text) {
  // ASCII is its own canonical form: most names never reach the normaliser.
  if (std::all_of(text.begin(), text.end(), [](char c) { return (c & 0x80) == 0; })) {
    return std::string(text);
  }
  // GLib stops at a NUL whatever the length given: "café\0xyz" came back as "café".
  if (text.find('\0') != std::string_view::npos) return std::string(text);
  const std::unique_ptr<gchar, decltype(&g_free)> composed(
      g_utf8_normalize(text.data(), static_cast<gssize>(text.size()), G_NORMALIZE_NFC), g_free);
  return composed ? std::string(composed.get()) : std::string(text);
}

}  // namespace pintag::db
