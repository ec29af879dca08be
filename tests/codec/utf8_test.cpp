#include "pintag/codec/utf8.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>

namespace pintag {
namespace {

// Code points at each length boundary with their encodings as the Unicode standard lists them.
struct Encoded {
  char32_t code_point;
  std::string bytes;
};
const Encoded kBoundaries[] = {
    {0x0000, std::string(1, '\0')}, {0x007F, "\x7F"},
    {0x0080, "\xC2\x80"},           {0x00E9, "\xC3\xA9"},  // é
    {0x07FF, "\xDF\xBF"},           {0x0800, "\xE0\xA0\x80"},
    {0x20AC, "\xE2\x82\xAC"},  // €
    {0xD7FF, "\xED\x9F\xBF"},       {0xE000, "\xEE\x80\x80"},
    {0xFFFF, "\xEF\xBF\xBF"},       {0x10000, "\xF0\x90\x80\x80"},
    {0x1D11E, "\xF0\x9D\x84\x9E"},  // musical G clef
    {0x10FFFF, "\xF4\x8F\xBF\xBF"},
};

TEST(Utf8, DecodesEveryLengthAtItsBoundaries) {
  for (const Encoded& e : kBoundaries) {
    const Utf8CodePoint decoded = DecodeUtf8(e.bytes, 0);
    EXPECT_EQ(decoded.value, e.code_point) << std::hex << static_cast<std::uint32_t>(e.code_point);
    EXPECT_EQ(decoded.length, e.bytes.size())
        << std::hex << static_cast<std::uint32_t>(e.code_point);
  }
}

TEST(Utf8, EncodesEveryLengthAtItsBoundaries) {
  for (const Encoded& e : kBoundaries) {
    std::string out = "x";
    AppendUtf8(out, e.code_point);
    EXPECT_EQ(out, "x" + e.bytes) << std::hex << static_cast<std::uint32_t>(e.code_point);
  }
}

TEST(Utf8, DecodesAtAnOffset) {
  const std::string text =
      "a\xE2\x82\xAC"
      "b";
  EXPECT_EQ(DecodeUtf8(text, 1).value, 0x20AC);
  EXPECT_EQ(DecodeUtf8(text, 1).length, 3U);
  EXPECT_EQ(DecodeUtf8(text, 4).value, U'b');
  EXPECT_EQ(DecodeUtf8(text, 2).length, 0U);  // inside the euro sign: a continuation byte
}

TEST(Utf8, RefusesWhatIsNotUtf8) {
  for (const std::string& bad : {
           std::string("\x80"),          // a continuation byte alone
           std::string("\xBF"),          //
           std::string("\xC3"),          // truncated two-byte sequence
           std::string("\xE2\x82"),      // truncated three-byte sequence
           std::string("\xF0\x9D\x84"),  // truncated four-byte sequence
           std::string("\xC3"
                       "A"),                     // a lead byte followed by ASCII
           std::string("\xC0\xAF"),              // overlong "/"
           std::string("\xC1\xBF"),              // overlong U+007F
           std::string("\xE0\x80\xAF"),          // overlong "/", three bytes
           std::string("\xE0\x9F\xBF"),          // overlong U+07FF
           std::string("\xF0\x8F\xBF\xBF"),      // overlong U+FFFF
           std::string("\xED\xA0\x80"),          // UTF-16 high surrogate U+D800
           std::string("\xED\xBF\xBF"),          // UTF-16 low surrogate U+DFFF
           std::string("\xF4\x90\x80\x80"),      // U+110000, beyond Unicode
           std::string("\xF8\x88\x80\x80\x80"),  // five-byte form
           std::string("\xFE"),
           std::string("\xFF"),
       }) {
    EXPECT_EQ(DecodeUtf8(bad, 0).length, 0U) << testing::PrintToString(bad);
  }
}

// A message quotes a long name cut short, never inside a character: a cut one would be invalid
// UTF-8 in a JSON answer (shown as U+FFFD, or refused by a strict client).
TEST(Utf8, QuotedPrefixCutsBetweenCharacters) {
  EXPECT_EQ(QuotedPrefix("delhi", 40), "'delhi'");
  EXPECT_EQ(QuotedPrefix("delhi", 5), "'delhi'");
  EXPECT_EQ(QuotedPrefix("delhi", 3), "'del\u2026'");
  EXPECT_EQ(QuotedPrefix("", 3), "''");
  const std::string delhi = "\u0926\u093f\u0932\u094d\u0932\u0940";  // 6 letters of 3 bytes
  for (std::size_t max_bytes = 0; max_bytes <= delhi.size() + 1; ++max_bytes) {
    const std::string quoted = QuotedPrefix(delhi, max_bytes);
    const std::size_t kept = max_bytes >= delhi.size() ? delhi.size() : max_bytes / 3 * 3;
    const std::string expected =
        "'" + delhi.substr(0, kept) + (kept < delhi.size() ? "\u2026" : "") + "'";
    EXPECT_EQ(quoted, expected) << max_bytes;
    for (std::size_t i = 0; i < quoted.size();) {
      const Utf8CodePoint point = DecodeUtf8(quoted, i);
      ASSERT_GT(point.length, 0U) << max_bytes << " at " << i;
      i += point.length;
    }
  }
}

}  // namespace
}  // namespace pintag
