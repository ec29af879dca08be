#include <gtest/gtest.h>

#include "label/label_utf8.hpp"

namespace pintag::label {
namespace {

TEST(LabelText, KeepsValidUtf8) {
  EXPECT_EQ(SanitizeUtf8("Connaught Place S.O"), "Connaught Place S.O");
  EXPECT_EQ(SanitizeUtf8("K\u0101raikk\u0101l"), "K\u0101raikk\u0101l");
  EXPECT_EQ(SanitizeUtf8("\u092A\u0941\u0923\u0947"), "\u092A\u0941\u0923\u0947");  // Devanagari
  EXPECT_EQ(SanitizeUtf8("\U0001F4E6 box"), "\U0001F4E6 box");
}

TEST(LabelText, ReplacesInvalidSequences) {
  EXPECT_EQ(SanitizeUtf8("a\xff"
                         "b"),
            "a\uFFFD"
            "b");
  EXPECT_EQ(SanitizeUtf8("a\xc3"), "a\uFFFD");            // truncated two-byte sequence
  EXPECT_EQ(SanitizeUtf8("\xc0\xaf"), "\uFFFD");          // overlong "/"
  EXPECT_EQ(SanitizeUtf8("\xed\xa0\x80"), "\uFFFD");      // a UTF-16 surrogate
  EXPECT_EQ(SanitizeUtf8("\xf4\x90\x80\x80"), "\uFFFD");  // beyond U+10FFFF
}

TEST(LabelText, DropsControlsAndFoldsSpaces) {
  EXPECT_EQ(SanitizeUtf8("  New\tDelhi\r\n  Head\x01 Office\x7f  "), "New Delhi Head Office");
  EXPECT_EQ(SanitizeUtf8("a\u202Eb\u200Fc"), "ab\u200Fc");  // bidi override removed
  EXPECT_EQ(SanitizeUtf8(std::string("a\0b", 3)), "ab");
  EXPECT_EQ(SanitizeUtf8(""), "");
}

TEST(LabelText, CutsVeryLongText) {
  const std::string long_text(10'000, 'x');
  EXPECT_EQ(SanitizeUtf8(long_text).size(), kMaxDrawnCodePoints);
  std::string long_multibyte;
  for (int i = 0; i < 1000; ++i) long_multibyte += "\u0101";
  EXPECT_EQ(SanitizeUtf8(long_multibyte).size(), 2 * kMaxDrawnCodePoints);
  // Whether it was cut: a bin cut short must be refused, not printed.
  bool cut = false;
  EXPECT_EQ(SanitizeUtf8(long_text, &cut).size(), kMaxDrawnCodePoints);
  EXPECT_TRUE(cut);
  const std::string at_limit(kMaxDrawnCodePoints, 'x');
  EXPECT_EQ(SanitizeUtf8(at_limit + " \t\x01 ", &cut), at_limit);  // only spaces and controls left
  EXPECT_FALSE(cut);
  // Cut at a space, it does not end in one.
  EXPECT_EQ(SanitizeUtf8(std::string(kMaxDrawnCodePoints - 1, 'x') + " yz", &cut),
            std::string(kMaxDrawnCodePoints - 1, 'x'));
  EXPECT_TRUE(cut);
}

}  // namespace
}  // namespace pintag::label
