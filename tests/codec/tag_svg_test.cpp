#include "pintag/codec/tag_svg.hpp"

#include <gtest/gtest.h>

#include <regex>
#include <string>
#include <vector>

#include "pintag/codec/geometry.hpp"
#include "pintag/codec/palette.hpp"

namespace pintag {
namespace {

// A small well-formedness check: every element closes in order, attributes are quoted, one root.
bool WellFormed(const std::string& xml, std::string* why) {
  std::vector<std::string> open;
  int roots = 0;
  std::size_t i = 0;
  while ((i = xml.find('<', i)) != std::string::npos) {
    const std::size_t end = xml.find('>', i);
    if (end == std::string::npos) return *why = "unterminated tag", false;
    const std::string tag = xml.substr(i + 1, end - i - 1);
    i = end + 1;
    if (tag.starts_with("?") || tag.starts_with("!")) continue;
    if (tag.starts_with("/")) {
      if (open.empty() || open.back() != tag.substr(1)) return *why = "mismatched </" + tag, false;
      open.pop_back();
      continue;
    }
    if (std::count(tag.begin(), tag.end(), '"') % 2 != 0) return *why = "unbalanced quotes", false;
    const std::string name = tag.substr(0, tag.find_first_of(" /"));
    if (open.empty()) ++roots;
    if (!tag.ends_with("/")) open.push_back(name);
  }
  if (!open.empty()) return *why = "unclosed <" + open.back(), false;
  if (roots != 1) return *why = "expected one root element", false;
  return true;
}

int Count(const std::string& text, const std::string& needle) {
  int n = 0;
  for (std::size_t i = text.find(needle); i != std::string::npos; i = text.find(needle, i + 1)) ++n;
  return n;
}

TEST(TagSvg, IsWellFormedWithEverySector) {
  const std::string svg = RenderTagSvg(TagKey(12345), {50, "mm"});
  std::string why;
  EXPECT_TRUE(WellFormed(svg, &why)) << why;
  EXPECT_EQ(Count(svg, "class=\"sector green\""), 32);
  EXPECT_EQ(Count(svg, "class=\"sector red\""), 16);
}

TEST(TagSvg, PhysicalSizeIsExactInMillimetres) {
  // 50 mm square + 0.15 × 50 mm quiet zone on each side = 65 mm.
  const std::string svg = RenderTagSvg(TagKey(1), {50, "mm"});
  EXPECT_NE(svg.find("width=\"65mm\" height=\"65mm\" viewBox=\"0 0 65 65\""), std::string::npos);
  EXPECT_NE(svg.find("<rect class=\"square\" x=\"7.5\" y=\"7.5\" width=\"50\" height=\"50\""),
            std::string::npos);
  const std::string px = RenderTagSvg(TagKey(1), {200, "px"});
  EXPECT_NE(px.find("width=\"260px\""), std::string::npos);
}

TEST(TagSvg, SectorColoursFollowTheBits) {
  // Key 0: payload and parity all 0, so every green sector is teal and C1 … C3's inner quadrants
  // crimson, the rest of C1 … C3 orange-red.
  const std::string svg = RenderTagSvg(TagKey(0));
  const auto hex = [](PaletteColour c) {
    char text[8];
    std::snprintf(text, sizeof text, "#%02x%02x%02x", SrgbFor(c).r, SrgbFor(c).g, SrgbFor(c).b);
    return std::string(text);
  };
  // Each cell once, plus each element's underlay (a disk of each bit-0 colour under its cells).
  EXPECT_EQ(Count(svg, "fill=\"" + hex(PaletteColour::kGreenZero) + "\""), 32 + 4);
  EXPECT_EQ(Count(svg, "fill=\"" + hex(PaletteColour::kRedOne) + "\""), 9);
  EXPECT_EQ(Count(svg, "fill=\"" + hex(PaletteColour::kRedZero) + "\""), 7 + 4);
}

TEST(TagSvg, EachElementLiesOnAnUnderlayOfItsBitZeroColoursSoNoSeamShowsTheSquare) {
  // Before its cells, each element draws a green-0 disk of the green ring's outer radius and a
  // red-0 disk of the red radius, centred on the element: an anti-aliased seam between two cells
  // then blends palette colours, not the black square (dark hairlines in a browser).
  const std::string svg = RenderTagSvg(TagKey(777), {100, "mm"});
  const std::regex underlay(
      R"re(<circle class="underlay (green|red)" cx="([0-9.]+)" cy="([0-9.]+)" r="([0-9.]+)")re");
  int green = 0;
  int red = 0;
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), underlay);
       it != std::sregex_iterator(); ++it) {
    const bool is_green = (*it)[1] == "green";
    (is_green ? green : red)++;
    // 100 mm square, 15 mm quiet zone: the radius is the geometry's times 100.
    EXPECT_NEAR(std::stod((*it)[4]),
                100 * (is_green ? geometry::kGreenOuterRadius : geometry::kRedRadius), 1e-3);
    const std::size_t at = static_cast<std::size_t>(it->position());
    const std::size_t first_cell = svg.find("class=\"sector", at);
    const std::size_t group_end = svg.find("</g>", at);
    EXPECT_LT(first_cell, group_end) << "the underlay lies under its own element's cells";
  }
  EXPECT_EQ(green, 4);
  EXPECT_EQ(red, 4);
}

}  // namespace
}  // namespace pintag
