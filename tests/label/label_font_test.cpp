#include "label/label_font.hpp"

#include <cairo.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "pintag/codec/utf8.hpp"

namespace pintag::label {
namespace {

// Vowel signs, viramas and other marks of Devanagari and Tamil, and the Latin combining
// diacritics: a line that starts with one shows it on a dotted circle, cut from its letter.
bool IsMark(char32_t c) {
  return (c >= 0x0300 && c <= 0x036F) || (c >= 0x0900 && c <= 0x0903) ||
         (c >= 0x093A && c <= 0x093C) || (c >= 0x093E && c <= 0x094F) ||
         (c >= 0x0951 && c <= 0x0957) || (c >= 0x0962 && c <= 0x0963) || c == 0x0B82 ||
         (c >= 0x0BBE && c <= 0x0BCD) || c == 0x0BD7;
}

class LabelFontTest : public ::testing::Test {
 protected:
  LabelFontTest()
      : surface_(cairo_image_surface_create(CAIRO_FORMAT_ARGB32, 8, 8), cairo_surface_destroy),
        cr_(cairo_create(surface_.get()), cairo_destroy),
        font_(cr_.get()) {}

  std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)> surface_;
  std::unique_ptr<cairo_t, decltype(&cairo_destroy)> cr_;
  LabelFont font_;
};

TEST_F(LabelFontTest, CutsNeverSeparateALetterFromItsSigns) {
  const std::vector<std::string> texts = {
      "\u0915\u094D\u0937\u0947\u0924\u094D\u0930\u0940\u092F\u0915\u093E\u0930\u094D\u092F"
      "\u093E\u0932\u092F",  // क्षेत्रीयकार्यालय
      "\u0B9A\u0BC6\u0BA9\u0BCD\u0BA9\u0BC8\u0BAE\u0BA4\u0BCD\u0BA4\u0BBF\u0BAF",  // சென்னைமத்திய
      "Ka\u0304raikka\u0304l-12",  // Kāraikkāl with its macrons as combining marks
  };
  for (const std::string& text : texts) {
    const std::vector<std::size_t> cuts = font_.cutPoints(text);
    ASSERT_GE(cuts.size(), 2U) << text;
    EXPECT_EQ(cuts.front(), 0U) << text;
    EXPECT_EQ(cuts.back(), text.size()) << text;
    std::size_t marks = 0;
    for (std::size_t i = 0; i < text.size();) {
      const Utf8CodePoint c = DecodeUtf8(text, i);
      ASSERT_GT(c.length, 0U) << text;
      marks += IsMark(c.value);
      i += c.length;
    }
    // Cuts fall between letters: as many as the text has letters, no more.
    std::size_t code_points = 0;
    for (std::size_t i = 0; i < text.size(); i += DecodeUtf8(text, i).length) ++code_points;
    EXPECT_GE(cuts.size() - 1, (code_points - marks) / 2) << text << ": too few places to cut";
    for (const std::size_t cut : cuts) {
      if (cut == text.size()) continue;
      const Utf8CodePoint c = DecodeUtf8(text, cut);
      ASSERT_GT(c.length, 0U) << text << ": cut inside a character at byte " << cut;
      EXPECT_FALSE(IsMark(c.value))
          << text << ": cut before the mark U+" << std::hex << static_cast<unsigned>(c.value)
          << " at byte " << std::dec << cut;
    }
  }
}

TEST_F(LabelFontTest, CutsNeverSplitAConjunct) {
  // Pango put a cursor position after each virama: क्|षे, स्|त्|र. A line cut there ended in a
  // visible halant and the next began with a bare consonant.
  const auto is_virama = [](char32_t c) {
    return c == 0x094D || c == 0x09CD || c == 0x0A4D || c == 0x0ACD || c == 0x0B4D || c == 0x0C4D ||
           c == 0x0CCD || c == 0x0D4D;
  };
  for (const std::string text : {
           "\u0915\u094D\u0937\u0947\u0924\u094D\u0930\u0940\u092F",  // क्षेत्रीय
           "\u0938\u094D\u0924\u094D\u0930",                          // स्त्र
           "\u0938\u094D\u0924\u094D\u0930\u0938\u094D\u0924\u094D\u0930",
           "\u0989\u09A4\u09CD\u09A4\u09B0",        // Bengali উত্তর
           "\u0C95\u0CB0\u0CCD\u0CA8\u0CBE\u0C9F",  // Kannada ಕರ್ನಾಟ
           "\u0915\u094D\u200D\u0937",              // a half form asked for with a ZWJ
       }) {
    const std::vector<std::size_t> cuts = font_.cutPoints(text);
    ASSERT_GE(cuts.size(), 2U) << text;
    for (const std::size_t cut : cuts) {
      if (cut == 0 || cut == text.size()) continue;
      std::size_t before = 0;  // the code point before the cut, through a ZWJ
      for (std::size_t i = 0; i < cut;) {
        const Utf8CodePoint c = DecodeUtf8(text, i);
        if (c.value != 0x200D) before = c.value;
        i += c.length;
      }
      EXPECT_FALSE(is_virama(static_cast<char32_t>(before)))
          << text << ": cut after a virama at byte " << cut;
    }
  }
  // Each conjunct is one piece: स्त्रस्त्र cuts once, between its two conjuncts.
  const std::string twice = "\u0938\u094D\u0924\u094D\u0930\u0938\u094D\u0924\u094D\u0930";
  EXPECT_EQ(font_.cutPoints(twice), (std::vector<std::size_t>{0, twice.size() / 2, twice.size()}));
  // Tamil writes a dead consonant apart from the next: மத்திய still cuts after its pulli.
  const std::string tamil = "\u0BAE\u0BA4\u0BCD\u0BA4\u0BBF\u0BAF";
  const std::size_t after_pulli = std::string("\u0BAE\u0BA4\u0BCD").size();
  const std::vector<std::size_t> cuts = font_.cutPoints(tamil);
  EXPECT_NE(std::find(cuts.begin(), cuts.end(), after_pulli), cuts.end());
}

TEST_F(LabelFontTest, AdvancesScaleWithTheSizeAndShapingJoinsConjuncts) {
  // Hinting off: a line twice the size is twice as wide, so a line fitted by one scaling step fits.
  const double small = font_.measure("Connaught Place S.O", false, 3).advance;
  const double large = font_.measure("Connaught Place S.O", false, 6).advance;
  EXPECT_GT(small, 0);
  EXPECT_NEAR(large, 2 * small, 1e-3 * large);
  // Shaped, क + ् + ष is one conjunct glyph, narrower than the three signs set side by side.
  const double conjunct = font_.advancePerSize("\u0915\u094D\u0937", true);
  const double apart = font_.advancePerSize("\u0915", true) + font_.advancePerSize("\u094D", true) +
                       font_.advancePerSize("\u0937", true);
  EXPECT_GT(conjunct, 0);
  EXPECT_LT(conjunct, 0.9 * apart);
}

// Urdu in one face. DejaVu Sans has most Arabic letters but not ہ or ے, so "ڈاک خانہ" came out
// in DejaVu with those two in Noto Naskh Arabic, thin letters among heavy ones inside a word.
TEST_F(LabelFontTest, UrduIsSetInNaskhWholeAndLatinBesideItInDejaVu) {
  for (const bool bold : {false, true}) {
    const std::vector<std::string> urdu = font_.familiesOf("ڈاک خانہ بہت بڑا ہے", bold);
    ASSERT_FALSE(urdu.empty());
    for (const std::string& family : urdu) EXPECT_EQ(family, "Noto Naskh Arabic") << bold;
    // A mixed line: the Latin and the digits stay in DejaVu, the Urdu (with the space between
    // its words) in Naskh.
    const std::vector<std::string> mixed = font_.familiesOf("Lahori Gate 110006 لاہوری گیٹ", bold);
    EXPECT_EQ(mixed.front(), "DejaVu Sans") << bold;
    EXPECT_EQ(mixed.back(), "Noto Naskh Arabic") << bold;
    for (const std::string& family : mixed) {
      EXPECT_TRUE(family == "DejaVu Sans" || family == "Noto Naskh Arabic") << family;
    }
  }
  // A mark on a run's last letter (a haraka, of no script of its own) stays in the run's face.
  for (const std::string& family : font_.familiesOf("ملتان\u064B", true)) {
    EXPECT_EQ(family, "Noto Naskh Arabic");
  }
  // Other scripts keep their faces.
  EXPECT_EQ(font_.familiesOf("Connaught Place", true), std::vector<std::string>{"DejaVu Sans"});
  EXPECT_EQ(font_.familiesOf("नई दिल्ली", true), std::vector<std::string>{"Noto Sans Devanagari"});
}

}  // namespace
}  // namespace pintag::label
