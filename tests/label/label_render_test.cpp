#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <optional>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "label/label_layout.hpp"
#include "label_test_util.hpp"
#include "pintag/codec/label.hpp"

namespace pintag {
namespace {

constexpr double kPointsPerMm = 72.0 / 25.4;

std::string AsText(const std::vector<std::uint8_t>& bytes) {
  return {bytes.begin(), bytes.end()};
}

/// What a poppler tool (`command`, e.g. "pdftotext -bbox") prints for `pdf`, written to a
/// scratch file for it (pdftotext is told "-", else it writes a file); nothing when it cannot run.
std::optional<std::string> Poppler(const std::string& command, const RenderedLabel& pdf) {
  test::TempDir dir;
  const auto path = dir.path() / "label.pdf";
  test::WriteFile(path, pdf.bytes);
  const bool to_stdout = command.rfind("pdftotext", 0) == 0;
  return test::Run(command + " '" + path.string() + "'" + (to_stdout ? " -" : ""));
}

// Every page's MediaBox (cairo writes them uncompressed in the page objects).
std::vector<std::pair<double, double>> MediaBoxes(const std::string& pdf) {
  static const std::regex kBox(R"(/MediaBox\s*\[\s*0\s+0\s+([0-9.]+)\s+([0-9.]+)\s*\])");
  std::vector<std::pair<double, double>> boxes;
  for (auto it = std::sregex_iterator(pdf.begin(), pdf.end(), kBox); it != std::sregex_iterator();
       ++it) {
    boxes.emplace_back(std::stod((*it)[1]), std::stod((*it)[2]));
  }
  return boxes;
}

TEST(LabelPdf, PageIsExactlyTheLabelSizeInPoints) {
  for (const LabelSize& size : {kLabel100x150, kLabelA6, kLabel4x6In, LabelSize{150, 100}}) {
    const RenderedLabel pdf = RenderLabelPdf(test::SampleLabel(), {size, 300});
    ASSERT_TRUE(pdf) << pdf.error;
    const std::string text = AsText(pdf.bytes);
    EXPECT_EQ(text.rfind("%PDF-", 0), 0U);
    const auto boxes = MediaBoxes(text);
    ASSERT_EQ(boxes.size(), 1U) << ToString(size);
    // cairo prints six decimals: exact to a millionth of a point.
    EXPECT_NEAR(boxes[0].first, size.width_mm * kPointsPerMm, 1e-5) << ToString(size);
    EXPECT_NEAR(boxes[0].second, size.height_mm * kPointsPerMm, 1e-5) << ToString(size);
  }
  // The numbers DESIGN.md quotes for the default label.
  const auto boxes = MediaBoxes(AsText(RenderLabelPdf(test::SampleLabel()).bytes));
  ASSERT_EQ(boxes.size(), 1U);
  EXPECT_NEAR(boxes[0].first, 283.465, 5e-4);
  EXPECT_NEAR(boxes[0].second, 425.197, 5e-4);
}

TEST(LabelPdf, PdfinfoReadsSizeAndPagesOfABatch) {
  if (!test::HavePoppler()) GTEST_SKIP() << "poppler-utils not installed";
  std::vector<LabelContent> labels;
  labels.reserve(50);
  for (int i = 0; i < 50; ++i) {
    labels.push_back(test::SampleLabel(110001 + static_cast<std::uint32_t>(i),
                                       static_cast<std::uint16_t>(1000 + 7 * i)));
  }
  const RenderedLabel pdf = RenderLabelsPdf(labels, {kLabel4x6In, 300});
  ASSERT_TRUE(pdf) << pdf.error;
  EXPECT_EQ(MediaBoxes(AsText(pdf.bytes)).size(), 50U);

  const auto info = Poppler("pdfinfo", pdf);
  ASSERT_TRUE(info.has_value());
  EXPECT_NE(info->find("Pages:           50\n"), std::string::npos) << *info;
  EXPECT_NE(info->find("Page size:       288 x 432 pts"), std::string::npos) << *info;
  EXPECT_NE(info->find("Title:           PinTag labels (50)"), std::string::npos) << *info;
}

TEST(LabelPdf, FontsAreEmbeddedSubsets) {
  if (!test::HavePoppler()) GTEST_SKIP() << "poppler-utils not installed";
  LabelContent label = test::SampleLabel();
  label.office = "K\u0101raikk\u0101l \u041C\u043E\u0441\u043A\u0432\u0430 B.O";
  const RenderedLabel pdf = RenderLabelPdf(label);
  ASSERT_TRUE(pdf) << pdf.error;
  const auto fonts = Poppler("pdffonts", pdf);
  ASSERT_TRUE(fonts.has_value());
  // Header, rule, then one row per font: "name type encoding emb sub uni object id".
  std::istringstream rows(*fonts);
  std::string row;
  int listed = 0;
  std::getline(rows, row);
  std::getline(rows, row);
  while (std::getline(rows, row)) {
    ++listed;
    EXPECT_NE(row.find("DejaVuSans"), std::string::npos) << row;
    EXPECT_TRUE(std::regex_search(row, std::regex(R"(\syes\s+yes\s)"))) << "not embedded: " << row;
  }
  EXPECT_GE(listed, 2) << *fonts;  // regular and bold
}

TEST(LabelPdf, RefusesAnEmptyBatchAndBadSizes) {
  const RenderedLabel empty = RenderLabelsPdf({}, {});
  EXPECT_FALSE(empty);
  EXPECT_TRUE(empty.bytes.empty());
  EXPECT_NE(empty.error.find("no labels"), std::string::npos);
  const RenderedLabel tiny = RenderLabelPdf(test::SampleLabel(), {LabelSize{20, 30}, 300});
  EXPECT_FALSE(tiny);
  EXPECT_NE(tiny.error.find("50 to 300 mm"), std::string::npos) << tiny.error;
}

TEST(LabelPng, RecordsDpiAndHasThePixelSizeOfSizeTimesDpi) {
  struct Case {
    LabelSize size;
    double dpi = 0;
    int width = 0;
    int height = 0;
  };
  for (const Case& c :
       {Case{kLabel100x150, 300, 1181, 1772}, Case{kLabel4x6In, 203, 812, 1218},
        Case{kLabelA6, 150, 620, 874}, Case{LabelSize{150, 100}, 600, 3543, 2362}}) {
    const RenderedLabel png = RenderLabelPng(test::SampleLabel(), {c.size, c.dpi});
    ASSERT_TRUE(png) << png.error;
    const auto decoded = test::ReadPng(png.bytes);
    ASSERT_TRUE(decoded.has_value());
    EXPECT_EQ(decoded->spec.width, c.width) << ToString(c.size) << " @ " << c.dpi;
    EXPECT_EQ(decoded->spec.height, c.height) << ToString(c.size) << " @ " << c.dpi;
    const PixelSize expected = LabelPixelSize({c.size, c.dpi});
    EXPECT_EQ(expected.width, c.width);
    EXPECT_EQ(expected.height, c.height);
    // PNG stores whole pixels per metre: 1 px/m is 0.0254 dpi.
    EXPECT_NEAR(decoded->spec.get_float_attribute("XResolution"), c.dpi, 0.0254);
    EXPECT_NEAR(decoded->spec.get_float_attribute("YResolution"), c.dpi, 0.0254);
    EXPECT_EQ(decoded->spec.get_string_attribute("ResolutionUnit"), "inch");
  }
}

TEST(LabelPng, RefusesOutOfRangeDpiAndPixelBombs) {
  for (double dpi : {0.0, 71.0, 1201.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    const RenderedLabel png = RenderLabelPng(test::SampleLabel(), {kLabel100x150, dpi});
    EXPECT_FALSE(png) << dpi;
    EXPECT_NE(png.error.find("dpi must be 72 to 1200"), std::string::npos) << png.error;
  }
  const RenderedLabel huge = RenderLabelPng(test::SampleLabel(), {LabelSize{300, 300}, 1200});
  EXPECT_FALSE(huge);
  EXPECT_NE(huge.error.find("megapixels"), std::string::npos) << huge.error;
  // The dpi as asked, not cut to a whole number.
  const RenderedLabel fractional =
      RenderLabelPng(test::SampleLabel(), {LabelSize{300, 150}, 1100.5});
  EXPECT_FALSE(fractional);
  EXPECT_NE(fractional.error.find("at 1100.5 dpi"), std::string::npos) << fractional.error;
  // The vector formats ignore dpi.
  EXPECT_TRUE(RenderLabelPdf(test::SampleLabel(), {kLabel100x150, 0}));
}

TEST(LabelSvg, TheSameLabelIsTheSameBytes) {
  // cairo numbered the page's group by every surface the process had made: three requests for
  // one label gave three different files (a review found), which defeats caching and diffing.
  const RenderedLabel first = RenderLabelSvg(test::SampleLabel());
  ASSERT_TRUE(RenderLabelPng(test::SampleLabel(), {kLabel100x150, 72}));  // more surfaces made
  const RenderedLabel second = RenderLabelSvg(test::SampleLabel());
  ASSERT_TRUE(first && second);
  EXPECT_EQ(first.bytes, second.bytes);
}

TEST(LabelPdf, TheSameLabelsAreTheSameBytes) {
  // cairo wrote the time of writing as /CreationDate: a label asked for twice differed.
  std::vector<LabelContent> labels = {test::SampleLabel(), test::SampleLabel(560001, 4321)};
  const RenderedLabel first = RenderLabelsPdf(labels, {kLabel100x150, 300});
  ASSERT_TRUE(RenderLabelPng(test::SampleLabel(), {kLabel100x150, 72}));  // more surfaces made
  const RenderedLabel second = RenderLabelsPdf(labels, {kLabel100x150, 300});
  ASSERT_TRUE(first && second) << first.error << second.error;
  EXPECT_EQ(first.bytes, second.bytes);
  // Renders within one second were equal before too: the date itself must be gone.
  EXPECT_EQ(AsText(first.bytes).find("/CreationDate"), std::string::npos);
  EXPECT_NE(AsText(first.bytes).find("/Creator (PinTag)"), std::string::npos);  // the rest stays
}

TEST(LabelSvg, IsSizedInMillimetresWithAPointViewBox) {
  const RenderedLabel svg = RenderLabelSvg(test::SampleLabel(), {kLabel4x6In, 300});
  ASSERT_TRUE(svg) << svg.error;
  const std::string text = AsText(svg.bytes);
  EXPECT_NE(text.find("<svg"), std::string::npos);
  EXPECT_NE(text.find("width=\"101.6000mm\" height=\"152.4000mm\""), std::string::npos)
      << text.substr(0, 400);
  EXPECT_NE(text.find("viewBox=\"0 0 288 432\""), std::string::npos) << text.substr(0, 400);
  EXPECT_NE(text.find("</svg>"), std::string::npos);
}

TEST(LabelText, IndianScriptsPrintInTheirOwnFacesAndReadBack) {
  if (!test::HavePoppler()) GTEST_SKIP() << "poppler-utils not installed";
  // DejaVu Sans has no Indian script: a Hindi bin printed as a row of boxes before.
  LabelContent label = test::SampleLabel();
  label.office =
      "\u0928\u0908 \u0926\u093F\u0932\u094D\u0932\u0940 \u092E\u0941\u0916\u094D\u092F "
      "\u0921\u093E\u0915\u0918\u0930";  // नई दिल्ली मुख्य डाकघर
  label.district = "\u0B9A\u0BC6\u0BA9\u0BCD\u0BA9\u0BC8";     // சென்னை
  label.state = "\u0C95\u0CB0\u0CCD\u0CA8\u0CBE\u0C9F\u0C95";  // ಕರ್ನಾಟಕ
  label.bin =
      "\u0995\u09B2\u0995\u09BE\u09A4\u09BE \u0989\u09A4\u09CD\u09A4\u09B0 7";  // কলকাতা উত্তর 7
  for (const LabelSize& size : {kLabel100x150, LabelSize{50, 75}}) {
    const RenderedLabel pdf = RenderLabelPdf(label, {size, 300});
    ASSERT_TRUE(pdf) << pdf.error;
    const auto fonts = Poppler("pdffonts", pdf);
    ASSERT_TRUE(fonts.has_value());
    for (const char* face : {"NotoSansDevanagari", "NotoSansTamil", "NotoSansKannada",
                             "NotoSansBengali", "DejaVuSans"}) {
      EXPECT_NE(fonts->find(face), std::string::npos)
          << ToString(size) << ": " << face << " not used (scripts/setup.sh installs "
          << "fonts-noto-core)\n"
          << *fonts;
    }
    // The words read back as written: each glyph run carries the text it was shaped from.
    const auto text = Poppler("pdftotext", pdf);
    ASSERT_TRUE(text.has_value());
    std::string words;
    for (const char c : *text) {
      if (std::isspace(static_cast<unsigned char>(c))) {
        if (!words.empty() && words.back() != ' ') words += ' ';
      } else {
        words += c;
      }
    }
    for (const std::string& written :
         {label.office, label.district + ", " + label.state, *label.bin}) {
      EXPECT_NE(words.find(written), std::string::npos)
          << ToString(size) << ": " << written << " not in: " << words;
    }
  }
}

TEST(LabelText, ALongBinIsPrintedWholeOnTwoLines) {
  if (!test::HavePoppler()) GTEST_SKIP() << "poppler-utils not installed";
  // Cut to one line, "Mumbai West Sorting Chute…" lost the chute's number, the part that sorts.
  LabelContent label = test::SampleLabel();
  label.bin = "Mumbai West Sorting Chute 12 Level 3 North Wing";
  for (const LabelSize& size : {kLabel100x150, kLabelA6, kLabel4x6In}) {
    const RenderedLabel pdf = RenderLabelPdf(label, {size, 300});
    ASSERT_TRUE(pdf) << pdf.error;
    const auto text = Poppler("pdftotext", pdf);
    ASSERT_TRUE(text.has_value());
    std::string words;  // the text with every run of whitespace made one space
    for (const char c : *text) {
      if (std::isspace(static_cast<unsigned char>(c))) {
        if (!words.empty() && words.back() != ' ') words += ' ';
      } else {
        words += c;
      }
    }
    EXPECT_NE(words.find("Mumbai West Sorting Chute 12 Level 3 North Wing"), std::string::npos)
        << words;
    EXPECT_EQ(words.find("\u2026"), std::string::npos) << words;
  }
  // A short bin stays on one line, as large as before.
  label.bin = "N-07";
  EXPECT_TRUE(RenderLabelPdf(label));
}

/// A word pdftotext found on a page, in points from the top-left corner. pdftotext's box runs
/// from the font's ascent to its descent; `top` and `bottom` are where the ink of capitals,
/// digits and short descenders lies (DejaVu Sans: ascent 0.928, descent 0.236, capitals 0.729 of
/// the size), which lines set close together must keep apart.
struct Word {
  std::string text;
  double x0, y0, x1, y1;
  double size() const { return (y1 - y0) / (0.928 + 0.236); }
  double baseline() const { return y1 - 0.236 * size(); }
  double top() const { return baseline() - 0.729 * size(); }
  double bottom() const { return baseline() + 0.12 * size(); }
};

/// The words of a one-page PDF with their boxes (`pdftotext -bbox`).
std::vector<Word> WordsOf(const RenderedLabel& pdf) {
  const auto html = Poppler("pdftotext -bbox", pdf);
  EXPECT_TRUE(html.has_value());
  static const std::regex kWord(
      R"re(<word xMin="([0-9.]+)" yMin="([0-9.]+)" xMax="([0-9.]+)" yMax="([0-9.]+)">([^<]*)</word>)re");
  std::vector<Word> words;
  if (!html) return words;
  for (auto it = std::sregex_iterator(html->begin(), html->end(), kWord);
       it != std::sregex_iterator(); ++it) {
    words.push_back({(*it)[5].str(), std::stod((*it)[1]), std::stod((*it)[2]), std::stod((*it)[3]),
                     std::stod((*it)[4])});
  }
  return words;
}

/// All text, whitespace removed: what a bin reads as, whichever lines it was broken onto.
std::string JoinedText(const std::vector<Word>& words) {
  std::string out;
  for (const Word& word : words) out += word.text;
  return out;
}

TEST(LabelLayout, TextStaysApartLegibleAndOffTheTagAtEverySize) {
  if (!test::HavePoppler()) GTEST_SKIP() << "poppler-utils not installed";
  // Long names everywhere, on the smallest sizes each layout allows and the usual ones. Before,
  // labels under about 93 mm tall ran their rows together (50 x 50 mm printed the bin upside
  // down across the frame) and shrank a wrapped office to 0.7 mm.
  LabelContent label = test::SampleLabel();
  label.office = "Kanchipuram Collectorate Buildings Extension S.O";
  label.district = "Thiruvananthapuram";
  label.state = "Andaman and Nicobar Islands";
  // Two lines on the small sizes; a longer bin is refused there (ABinIsPrintedWholeOrTheLabel…).
  label.bin = "BLR-CHUTE-12";
  label.plan = "north-hub-night";
  constexpr double kMinSizePt = 1.4 * kPointsPerMm;  // the small print's floor
  for (const LabelSize& size :
       {kLabel100x150, kLabelA6, kLabel4x6In, LabelSize{50, 75}, LabelSize{75, 75},
        LabelSize{60, 90}, LabelSize{80, 80}, LabelSize{50, 100}, LabelSize{75, 50},
        LabelSize{100, 50}, LabelSize{150, 300}, LabelSize{300, 150}}) {
    const RenderedLabel pdf = RenderLabelPdf(label, {size, 300});
    ASSERT_TRUE(pdf) << ToString(size) << ": " << pdf.error;
    const std::vector<Word> words = WordsOf(pdf);
    ASSERT_GE(words.size(), 10U) << ToString(size);
    const LabelTagPlacement tag = TagPlacement(size);
    const double quiet = 0.15 * tag.square_side_mm;
    const double tag_x0 = (tag.square_x_mm - quiet) * kPointsPerMm;
    const double tag_y0 = (tag.square_y_mm - quiet) * kPointsPerMm;
    const double tag_x1 = (tag.square_x_mm + tag.square_side_mm + quiet) * kPointsPerMm;
    const double tag_y1 = (tag.square_y_mm + tag.square_side_mm + quiet) * kPointsPerMm;
    for (std::size_t i = 0; i < words.size(); ++i) {
      const Word& a = words[i];
      const std::string where = ToString(size) + " '" + a.text + "'";
      EXPECT_GT(a.x1, a.x0) << where;  // drawn left to right, not mirrored by a negative size
      EXPECT_GE(a.size(), kMinSizePt) << where;
      EXPECT_GE(a.x0, 3 * kPointsPerMm) << where;
      EXPECT_LE(a.x1, (size.width_mm - 3) * kPointsPerMm) << where;
      EXPECT_GE(a.y0, 3 * kPointsPerMm) << where;
      EXPECT_LE(a.y1, (size.height_mm - 3) * kPointsPerMm) << where;
      const bool on_tag = a.x1 > tag_x0 && a.x0 < tag_x1 && a.y1 > tag_y0 && a.y0 < tag_y1;
      EXPECT_FALSE(on_tag) << where << " lies on the tag or its quiet zone";
      for (std::size_t j = i + 1; j < words.size(); ++j) {
        const Word& b = words[j];
        const double across = std::min(a.x1, b.x1) - std::max(a.x0, b.x0);
        const double down = std::min(a.bottom(), b.bottom()) - std::max(a.top(), b.top());
        EXPECT_FALSE(across > 0.2 && down > 0)
            << where << " overlaps '" << b.text << "' by " << across << " x " << down << " pt";
      }
    }
  }
}

TEST(LabelText, APlanNameTooLongToPrintKeepsBothEnds) {
  if (!test::HavePoppler()) GTEST_SKIP() << "poppler-utils not installed";
  // Cut at the end, plans named alike at the start printed alike beside their bins: both of these
  // were "plan mumbai-central-sorting-hub-…". On the usual sizes; on the smallest the plan's
  // corner holds a few characters either way.
  const std::string start = "mumbai-central-sorting-hub-north-wing-conveyor-line-";
  for (const LabelSize& size : {kLabel100x150, kLabelA6, kLabel4x6In}) {
    for (const std::string end : {"inbound", "outbound"}) {
      LabelContent label = test::SampleLabel();
      label.plan = start + end;
      const RenderedLabel pdf = RenderLabelPdf(label, {size, 300});
      ASSERT_TRUE(pdf) << pdf.error;
      const std::string text = JoinedText(WordsOf(pdf));
      const std::string where = ToString(size) + " " + *label.plan + ": " + text;
      EXPECT_NE(text.find("\u2026"), std::string::npos) << where;  // too long: the test cuts
      EXPECT_NE(text.find("planmumbai-central-s"), std::string::npos) << where;
      EXPECT_NE(text.find(end), std::string::npos) << where;
      EXPECT_EQ(text.find(start), std::string::npos) << where;
    }
  }
}

TEST(LabelText, ABinIsPrintedWholeOrTheLabelIsRefused) {
  if (!test::HavePoppler()) GTEST_SKIP() << "poppler-utils not installed";
  // A bin without spaces was cut to one line at 3 mm and ellipsized: "…-CHUTE-12" and
  // "…-CHUTE-13" both printed "BLR-OUTBOUND-CONVEYOR-…". Then the end was kept and the start cut,
  // and "Kolkata Inbound Bay 12" and "Kolkata Outbound Bay 12" both printed "Kolkata… / nd Bay
  // 12" on a 70 x 50 mm label. A bin is the part a sorter acts on: it prints whole, or the label
  // is refused saying why.
  const std::vector<std::string> bins = {
      "BLR-OUTBOUND-CONVEYOR-CHUTE-12",
      std::string(54, 'W') + "CHUTE12",                                   // no break at all
      "Mumbai West Sorting Chute Level Three North Wing Chute 12",        // 64 bytes, spaces
      "Bengaluru_Outbound/Conveyor.Line:Chute_Level_3_North_Wing_Chu12",  // 64 bytes, punctuation
      "Kolkata Inbound Bay 12",
      "Kolkata Outbound Bay 12",
      "N-07"};
  std::size_t printed = 0;
  std::size_t refused = 0;
  for (const LabelSize& size : {kLabel100x150, LabelSize{50, 75}, LabelSize{75, 75},
                                LabelSize{100, 50}, LabelSize{75, 50}, LabelSize{70, 50}}) {
    for (const std::string& bin : bins) {
      LabelContent label = test::SampleLabel();
      label.bin = bin;
      const std::string where = ToString(size) + " '" + bin + "'";
      const RenderedLabel pdf = RenderLabelPdf(label, {size, 300});
      const RenderedLabel png = RenderLabelPng(label, {size, 150});
      const RenderedLabel svg = RenderLabelSvg(label, {size, 300});
      EXPECT_EQ(static_cast<bool>(png), static_cast<bool>(pdf)) << where;
      EXPECT_EQ(static_cast<bool>(svg), static_cast<bool>(pdf)) << where;
      // In a batch, between labels that print, the same verdict and reason (a batch checks its
      // bins before it draws a page).
      LabelContent short_bin = test::SampleLabel();
      short_bin.bin = "N-07";
      const std::vector<LabelContent> batch = {short_bin, label, short_bin};
      const RenderedLabel batched = RenderLabelsPdf(batch, {size, 300});
      EXPECT_EQ(static_cast<bool>(batched), static_cast<bool>(pdf)) << where;
      if (!pdf) {
        EXPECT_EQ(batched.refused_label, std::optional<std::size_t>{1}) << where;
        EXPECT_EQ(batched.error, pdf.error) << where;
      }
      if (!pdf) {
        ++refused;
        EXPECT_NE(pdf.error.find("'" + bin + "'"), std::string::npos) << where << pdf.error;
        EXPECT_NE(pdf.error.find("too long to print whole"), std::string::npos) << pdf.error;
        EXPECT_TRUE(pdf.bytes.empty());
        continue;
      }
      ++printed;
      std::string whole = bin;
      std::erase(whole, ' ');
      // Whole and in order (the plan's name beside it may still be ellipsized).
      const std::string text = JoinedText(WordsOf(pdf));
      EXPECT_NE(text.find(whole), std::string::npos) << where << " printed as " << text;
    }
  }
  // Both outcomes happen on these sizes: the check is not vacuous either way.
  EXPECT_GT(printed, 15U);
  EXPECT_GT(refused, 5U);
  // Printed, with every character of the bin in order (spaces aside: lines break at them).
  const auto expect_printed_whole = [](const LabelSize& size, const std::string& bin) {
    LabelContent label = test::SampleLabel();
    label.bin = bin;
    const RenderedLabel pdf = RenderLabelPdf(label, {size, 300});
    ASSERT_TRUE(pdf) << ToString(size) << " " << bin << ": " << pdf.error;
    std::string whole = bin;
    std::erase(whole, ' ');
    EXPECT_NE(JoinedText(WordsOf(pdf)).find(whole), std::string::npos)
        << ToString(size) << " " << bin;
  };
  // A bin whose only space or punctuation falls where the lines would not fit breaks between
  // other characters instead: these were refused although two lines hold them (a review found).
  for (const auto& [size, bin] :
       {std::pair{kLabel100x150, "Hub 7 ConsolidationAndReturnsProcessingCentreNorth"},
        std::pair{kLabel100x150, "X NNNNNNNNNNNNNNNNNNNNNNNNNNNNNN"},
        std::pair{LabelSize{50, 75}, "A CHUTEONETWOTHREE"},
        std::pair{LabelSize{50, 75}, "NNNNNNNNN N-NNNNNNNNNNNN"}}) {
    expect_printed_whole(size, bin);
  }
  // The usual sizes print a 64-byte bin of words whole; 61 of the widest letter do not fit even
  // there. 64 bytes of capitals with wide letters (M, W) do not fit two lines at the floor: they
  // go on three (a plan was accepted whose labels were then all refused, an API walkthrough found).
  const std::vector<std::string> capitals = {
      "MUMBAI WAREHOUSE WEST MEZZANINE WING DOCK MWMW NUMBER TWELVE MMM",
      "BHUBANESWAR-NORTH-WAREHOUSE-MEZZANINE-DOCK-WWMM-OVERFLOW-BAY-12"};
  for (const LabelSize& size : {kLabel100x150, kLabelA6, kLabel4x6In}) {
    for (const std::string& bin :
         {bins[0], bins[2], bins[3], bins[4], bins[5], capitals[0], capitals[1]}) {
      expect_printed_whole(size, bin);
    }
  }
}

TEST(LabelText, ABinBreaksBetweenWordsNotInsideThem) {
  if (!test::HavePoppler()) GTEST_SKIP() << "poppler-utils not installed";
  // With one space, punctuation was not a place to break: "A BLR-OUT" / "BOUND-CONVEYOR-…".
  LabelContent label = test::SampleLabel();
  label.bin = "A BLR-OUTBOUND-CONVEYOR-CHUTE-12";
  const RenderedLabel pdf = RenderLabelPdf(label, {LabelSize{75, 75}, 300});
  ASSERT_TRUE(pdf) << pdf.error;
  const auto text = Poppler("pdftotext -layout", pdf);
  ASSERT_TRUE(text.has_value());
  EXPECT_NE(text->find("A BLR-OUTBOUND-"), std::string::npos) << *text;
  EXPECT_NE(text->find("CONVEYOR-CHUTE-12"), std::string::npos) << *text;
}

TEST(LabelText, ABatchIsRefusedAtItsFirstLabelWhoseBinDoesNotPrint) {
  // Bins that repeat are tried once; the refusal names the first label that cannot print, as
  // drawing page by page would, whatever bins follow it.
  const auto with_bin = [](std::uint32_t pincode, std::optional<std::string> bin) {
    LabelContent label = test::SampleLabel(pincode);
    label.bin = std::move(bin);
    return label;
  };
  const std::string too_long = std::string(54, 'W') + "CHUTE12";
  const std::string also_too_long = std::string(60, 'M');
  const std::vector<LabelContent> batch = {
      with_bin(110001, "N-07"),        with_bin(110002, std::nullopt), with_bin(110003, "N-07"),
      with_bin(110004, also_too_long), with_bin(110005, too_long),     with_bin(110006, "N-07")};
  const LabelOptions small{LabelSize{70, 50}, 300};
  const RenderedLabel refused = RenderLabelsPdf(batch, small);
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.refused_label, std::optional<std::size_t>{3});
  EXPECT_NE(refused.error.find("'" + also_too_long + "' of pincode 110004"), std::string::npos)
      << refused.error;
  EXPECT_TRUE(refused.bytes.empty());
  // Without the two long bins the other four print, a page each.
  const std::vector<LabelContent> printable = {batch[0], batch[1], batch[2], batch[5]};
  const RenderedLabel printed = RenderLabelsPdf(printable, small);
  ASSERT_TRUE(printed) << printed.error;
  EXPECT_EQ(MediaBoxes(AsText(printed.bytes)).size(), 4U);
}

TEST(LabelText, HostileNamesStillRender) {
  LabelContent label = test::SampleLabel();
  label.office = std::string(5000, 'W') + "\xff\xfe\x01\x02 \u202E evil";
  label.district = "\xe0\xa4";  // truncated Devanagari lead bytes
  label.state = "";
  label.bin =
      "\xff"
      "9\x01-\u202E9";
  label.plan = "\n\t";
  EXPECT_TRUE(RenderLabelPdf(label));
  EXPECT_TRUE(RenderLabelSvg(label));
  EXPECT_TRUE(RenderLabelPng(label, {kLabelA6, 96}));
  // A bin no label can hold whole (the registry keeps bins to 64 bytes) is a refusal, not a cut.
  label.bin = std::string(300, '9');
  for (const RenderedLabel& refused :
       {RenderLabelPdf(label), RenderLabelSvg(label), RenderLabelPng(label, {kLabelA6, 96})}) {
    EXPECT_FALSE(refused);
    EXPECT_NE(refused.error.find("too long to print whole"), std::string::npos) << refused.error;
  }
  label.office.clear();
  label.district.clear();
  label.bin.reset();
  label.plan.reset();
  EXPECT_TRUE(RenderLabelPdf(label));
  EXPECT_TRUE(RenderLabelPng(label, {kLabelA6, 96}));
}

/// The rows where two renders of one size differ: [first, last], or nothing when they do not.
std::optional<std::pair<int, int>> RowsThatDiffer(const RgbImage& a, const RgbImage& b) {
  std::optional<std::pair<int, int>> rows;
  for (int y = 0; y < a.height; ++y) {
    for (int i = y * a.width * 3; i < (y + 1) * a.width * 3; ++i) {
      if (a.pixels[static_cast<std::size_t>(i)] == b.pixels[static_cast<std::size_t>(i)]) continue;
      rows = rows ? std::make_pair(rows->first, y) : std::make_pair(y, y);
      break;
    }
  }
  return rows;
}

TEST(LabelText, StackedMarksStayOnTheirOwnRow) {
  // A name of one letter and 99 combining accents (the API accepts it) drew its accents up
  // through "PIN CODE" and the pincode digits and off the label; a Tibetan stack of subjoined
  // letters ran down over the bin. Each line's ink is now held to its row.
  constexpr int kDpi = 200;
  const double px_per_mm = kDpi / 25.4;
  std::string accents;
  for (int i = 0; i < 99; ++i) accents += "\u0301";
  std::string tibetan_stack = "\u0F40";
  for (int i = 0; i < 40; ++i) tibetan_stack += "\u0F90";
  struct Case {
    const char* what;
    std::string LabelContent::*field;
    std::string plain;
    std::string hostile;
    double row_mm;  ///< the largest line size that field prints at on 100 x 150 mm
  };
  const Case cases[] = {
      {"office", &LabelContent::office, "A", "A" + accents, 7.0},
      {"district", &LabelContent::district, "Nagar ", "Nagar " + tibetan_stack, 4.6}};
  for (const Case& c : cases) {
    LabelContent plain = test::SampleLabel();
    plain.*c.field = c.plain;
    LabelContent hostile = plain;
    hostile.*c.field = c.hostile;
    const RenderedLabel a = RenderLabelPng(plain, {kLabel100x150, kDpi});
    const RenderedLabel b = RenderLabelPng(hostile, {kLabel100x150, kDpi});
    ASSERT_TRUE(a && b) << a.error << b.error;
    const auto pa = test::ReadPng(a.bytes);
    const auto pb = test::ReadPng(b.bytes);
    ASSERT_TRUE(pa && pb);
    const auto rows = RowsThatDiffer(pa->image, pb->image);
    ASSERT_TRUE(rows.has_value()) << c.what << ": the marks were not drawn at all";
    const double span_mm = (rows->second - rows->first + 1) / px_per_mm;
    // Within the line's band (1.3 sizes above the baseline, 0.6 below).
    EXPECT_LE(span_mm, 1.9 * c.row_mm + 0.5)
        << c.what << ": rows " << rows->first << " to " << rows->second;
  }
  // A bin of stacked accents keeps off the pincode, which prints above the bin's box.
  LabelContent plain = test::SampleLabel();
  plain.bin = "B";
  LabelContent hostile = plain;
  hostile.bin = "B" + accents.substr(0, std::size_t{31} * 2);  // 31 accents of 2 bytes
  const auto pa = test::ReadPng(RenderLabelPng(plain, {kLabel100x150, kDpi}).bytes);
  const auto pb = test::ReadPng(RenderLabelPng(hostile, {kLabel100x150, kDpi}).bytes);
  ASSERT_TRUE(pa && pb);
  const auto rows = RowsThatDiffer(pa->image, pb->image);
  ASSERT_TRUE(rows.has_value());
  EXPECT_LE((rows->second - rows->first + 1) / px_per_mm, 1.9 * 14.0 + 0.5);
}

TEST(LabelLayout, TagIsLargeAndItsQuietZoneStaysOnTheLabel) {
  for (const LabelSize& size :
       {kLabel100x150, kLabelA6, kLabel4x6In, LabelSize{150, 100}, LabelSize{75, 75},
        LabelSize{50, 75}, LabelSize{150, 300}, LabelSize{300, 150}, LabelSize{100, 100}}) {
    ASSERT_TRUE(ValidateLabelSize(size).empty()) << ValidateLabelSize(size);
    const LabelTagPlacement p = TagPlacement(size);
    const double quiet = 0.15 * p.square_side_mm;
    // The smallest labels give their text rows a fixed least height; the rest a third or more.
    const double shorter = std::min(size.width_mm, size.height_mm);
    EXPECT_GE(p.square_side_mm, shorter >= 100 ? 0.32 * shorter : kMinLabelTagSideMm)
        << ToString(size);
    EXPECT_GE(p.square_x_mm - quiet, 3.0) << ToString(size);
    EXPECT_GE(p.square_y_mm - quiet, 3.0) << ToString(size);
    EXPECT_LE(p.square_x_mm + p.square_side_mm + quiet, size.width_mm - 3.0) << ToString(size);
    EXPECT_LE(p.square_y_mm + p.square_side_mm + quiet, size.height_mm - 3.0) << ToString(size);
  }
  EXPECT_GT(TagPlacement(kLabel100x150).square_side_mm, 50.0);
}

/// The words of `pdf` whose text is one of `names`' words, in order found.
std::vector<Word> WordsFrom(const std::vector<Word>& words, const std::string& names) {
  std::vector<Word> found;
  std::istringstream in(names);
  std::vector<std::string> wanted;
  for (std::string word; in >> word;) wanted.push_back(word);
  for (const Word& word : words) {
    if (std::find(wanted.begin(), wanted.end(), word.text) != wanted.end()) found.push_back(word);
  }
  return found;
}

TEST(LabelText, ALongOfficeNamePrintsWholeOnTwoLinesOfOneSize) {
  if (!test::HavePoppler()) GTEST_SKIP() << "poppler-utils not installed";
  // The first line took as many words as fit at the two-line size and the second shrank alone,
  // then was cut ("…upati Urban North" lost), though two balanced lines held the whole name.
  for (const auto& [size, office] :
       {std::pair{kLabel100x150,
                  "Sri Venkateswara Nagar Extension Colony Branch Post Office Near Old Railway "
                  "Station Road Tirupati Urban North"},
        std::pair{LabelSize{70, 50}, "Old Town Market Yard East S.O"}}) {
    LabelContent label = test::SampleLabel();
    label.office = office;
    label.district = "Chittoor";
    label.state = "Andhra Pradesh";
    const RenderedLabel pdf = RenderLabelPdf(label, {size, 300});
    ASSERT_TRUE(pdf) << pdf.error;
    const std::vector<Word> words = WordsOf(pdf);
    const std::string where = ToString(size) + " '" + label.office + "': " + JoinedText(words);
    std::string whole = label.office;
    std::erase(whole, ' ');
    EXPECT_NE(JoinedText(words).find(whole), std::string::npos) << where;  // not ellipsized
    const std::vector<Word> office_words = WordsFrom(words, label.office);
    ASSERT_FALSE(office_words.empty()) << where;
    EXPECT_GT(office_words.back().baseline(), office_words.front().baseline() + 1)
        << where << ": one line";
    for (const Word& word : office_words) {
      EXPECT_NEAR(word.size(), office_words.front().size(), 0.02)
          << where << " '" << word.text << "'";
    }
  }
}

TEST(LabelLayout, TheBinKeepsAGutterFromTheSmallPrint) {
  if (!test::HavePoppler()) GTEST_SKIP() << "poppler-utils not installed";
  // The bin's column ended where the small print's began: "Bay 12" ran into "key 4321" with
  // 0.1 mm between them on 70 x 50 mm.
  for (const auto& [size, bin] :
       {std::pair{LabelSize{70, 50}, "Bay 12"}, std::pair{LabelSize{75, 50}, "Bay 12"},
        std::pair{kLabel100x150, "WWWWWWW-12"}}) {
    LabelContent label = test::SampleLabel(110001, 32767);  // the widest key, whole
    label.bin = bin;
    const RenderedLabel pdf = RenderLabelPdf(label, {size, 300});
    ASSERT_TRUE(pdf) << pdf.error;
    const std::vector<Word> words = WordsOf(pdf);
    const std::string where = ToString(size) + " '" + bin + "': " + JoinedText(words);
    const std::vector<Word> bin_words = WordsFrom(words, bin);
    const std::vector<Word> small_print = WordsFrom(words, "key 32767 PinTag v1");
    ASSERT_EQ(bin_words.size(), std::string(bin).find(' ') == std::string::npos ? 1U : 2U) << where;
    ASSERT_EQ(small_print.size(), 4U) << where;
    double bin_right = 0;
    for (const Word& word : bin_words) bin_right = std::max(bin_right, word.x1);
    // It fills its column: the gap is the gutter, not room left over.
    const label::LabelLayout layout = label::ComputeLayout(size);
    EXPECT_GT(bin_right, (layout.bin.x + 0.58 * layout.bin.w - 4) * kPointsPerMm) << where;
    for (const Word& word : small_print) {
      EXPECT_GE(word.x0 - bin_right, 1.0 * kPointsPerMm) << where << " '" << word.text << "'";
    }
  }
}

TEST(LabelText, MarksOverTheBinStayClearOfItsCaption) {
  // A one-line bin is set large, and a tilde stacked over a circumflex ("Ỗ") ran through the N of
  // "SORT BIN" above it: the caption's rows are to hold the caption alone, whatever the bin.
  constexpr double kDpi = 300;
  const double px_per_mm = kDpi / 25.4;
  std::string accents = "B";
  for (int i = 0; i < 12; ++i) accents += "\u0301";
  for (const LabelSize& size : {kLabel100x150, LabelSize{70, 50}}) {
    const label::Box box = label::ComputeLayout(size).bin;
    // From the box's rule to a little under the caption's baseline (2 mm pad, 2.4 mm caption).
    const int from = static_cast<int>((box.y + 0.5) * px_per_mm);
    const int to = static_cast<int>(std::ceil((box.y + 2.0 + 0.75 * 2.4 + 0.2) * px_per_mm));
    LabelContent plain = test::SampleLabel();
    plain.bin.reset();
    const auto without = test::ReadPng(RenderLabelPng(plain, {size, kDpi}).bytes);
    ASSERT_TRUE(without);
    for (const std::string& bin :
         {std::string("\u01FA\u1ED6 7"), std::string("\u1ED6\u1EAA"), accents}) {
      LabelContent label = plain;
      label.bin = bin;
      const RenderedLabel png = RenderLabelPng(label, {size, kDpi});
      ASSERT_TRUE(png) << png.error;
      const auto with = test::ReadPng(png.bytes);
      ASSERT_TRUE(with);
      int differ = 0;
      for (int y = from; y <= to; ++y) {
        for (int x = 0; x < with->image.width; ++x) {
          for (int c = 0; c < 3; ++c) {
            const std::size_t i = (static_cast<std::size_t>(y) * with->image.width + x) * 3 + c;
            differ += with->image.pixels[i] != without->image.pixels[i];
          }
        }
      }
      EXPECT_EQ(differ, 0) << ToString(size) << " '" << bin << "': the bin's ink reaches rows "
                           << from << " to " << to;
    }
  }
}

TEST(LabelText, DevanagariBinLinesNeverEndInAVirama) {
  if (!test::HavePoppler()) GTEST_SKIP() << "poppler-utils not installed";
  // Broken between स् and त्र, a line ended in a visible halant and the conjunct was lost.
  for (const auto& [size, repeats] :
       {std::pair{LabelSize{70, 50}, 5}, std::pair{LabelSize{70, 50}, 7},
        std::pair{LabelSize{50, 75}, 9}}) {
    LabelContent label = test::SampleLabel();
    std::string bin;
    for (int i = 0; i < repeats; ++i) bin += "\u0938\u094D\u0924\u094D\u0930";  // स्त्र
    label.bin = bin;
    const RenderedLabel pdf = RenderLabelPdf(label, {size, 300});
    ASSERT_TRUE(pdf) << ToString(size) << " " << repeats << ": " << pdf.error;
    const auto text = Poppler("pdftotext", pdf);
    ASSERT_TRUE(text.has_value());
    EXPECT_NE(JoinedText(WordsOf(pdf)).find(bin), std::string::npos) << *text;
    std::istringstream lines(*text);
    int bin_lines = 0;
    for (std::string line; std::getline(lines, line);) {
      if (line.find("\u0938") == std::string::npos) continue;
      ++bin_lines;
      while (!line.empty() && line.back() == ' ') line.pop_back();
      EXPECT_FALSE(line.ends_with("\u094D")) << ToString(size) << ": '" << line << "'";
    }
    EXPECT_EQ(bin_lines, 2) << ToString(size) << " " << repeats << ": " << *text;
  }
  // An ellipsized name keeps its conjuncts too: never "क्…".
  LabelContent label = test::SampleLabel();
  label.office.clear();
  for (int i = 0; i < 60; ++i) label.office += "\u0915\u094D\u0937";  // क्ष
  const auto text = Poppler("pdftotext", RenderLabelPdf(label, {LabelSize{50, 75}, 300}));
  ASSERT_TRUE(text.has_value());
  EXPECT_NE(text->find("\u2026"), std::string::npos) << *text;
  EXPECT_EQ(text->find("\u094D\u2026"), std::string::npos) << *text;
}

TEST(LabelText, ABinLongerThanALabelDrawsIsRefusedNotCut) {
  // Text is cut to 200 code points before it is measured: 215 "i" and "CHUTE9" fit a 300 x 150
  // mm label's two lines once cut, and printed 200 i's without the chute.
  LabelContent label = test::SampleLabel();
  label.bin = std::string(215, 'i') + "CHUTE9";
  for (const RenderedLabel& refused : {RenderLabelPdf(label, {LabelSize{300, 150}, 300}),
                                       RenderLabelPng(label, {LabelSize{300, 150}, 72})}) {
    EXPECT_FALSE(refused);
    EXPECT_NE(refused.error.find("too long to print whole"), std::string::npos) << refused.error;
    EXPECT_FALSE(refused.internal_error);  // the content's fault: a 400, not a 500
  }
  // The same at the limit prints.
  label.bin = std::string(194, 'i') + "CHUTE9";
  EXPECT_TRUE(RenderLabelPdf(label, {LabelSize{300, 150}, 300}));
  // A name cut at the limit shows it.
  if (!test::HavePoppler()) GTEST_SKIP() << "poppler-utils not installed";
  label.office.clear();
  for (int i = 0; i < 30; ++i) label.office += "iiiiiiiii ";
  const RenderedLabel pdf = RenderLabelPdf(label, {LabelSize{300, 150}, 300});
  ASSERT_TRUE(pdf) << pdf.error;
  const std::string text = JoinedText(WordsOf(pdf));
  EXPECT_NE(text.find(std::string(180, 'i') + "\u2026"), std::string::npos) << text;
}

}  // namespace
}  // namespace pintag
