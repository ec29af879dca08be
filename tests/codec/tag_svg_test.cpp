#include "pintag/codec/tag_svg.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <regex>
#include <string>
#include <vector>

#include "pintag/codec/cells.hpp"
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

std::string Hex(PaletteColour c) {
  char text[8];
  std::snprintf(text, sizeof text, "#%02x%02x%02x", SrgbFor(c).r, SrgbFor(c).g, SrgbFor(c).b);
  return text;
}

TEST(TagSvg, SectorColoursFollowTheBits) {
  // Each cell's path read back from the file (rsvg is not a dependency): its outline located in
  // the format's geometry, its fill compared with the codec's own bits, as the PNG tests do.
  // Counting fills alone, for key 0, passed with sectors swapped or angles mirrored.
  constexpr double kSide = 100;  // mm; the square's corner is at 15, 15
  const std::regex path(
      R"re(<path class="sector (green|red)" d="([^"]*)" fill="(#[0-9a-f]{6})")re");
  const std::regex number(R"(-?[0-9.]+)");
  for (const std::uint16_t value : {0, 1, 777, 12345, 21845, 32767}) {
    const TagKey key(value);
    const TagCells cells = EncodeCells(key);
    const std::string svg = RenderTagSvg(key, {kSide, "mm"});
    std::array<std::array<int, kGreenSectors>, kElements> green_seen{};
    std::array<std::array<int, kRedQuadrants>, kElements> red_seen{};
    for (auto it = std::sregex_iterator(svg.begin(), svg.end(), path); it != std::sregex_iterator();
         ++it) {
      const bool is_green = (*it)[1] == "green";
      const std::string d = (*it)[2];
      std::vector<double> v;
      for (auto n = std::sregex_iterator(d.begin(), d.end(), number); n != std::sregex_iterator();
           ++n) {
        v.push_back(std::stod(n->str()));
      }
      // Green: M p0 A r,r 0 0 1 p1 L p2 A r,r 0 0 0 p3; red: M centre L p0 A r,r 0 0 1 p1.
      ASSERT_EQ(v.size(), is_green ? 18U : 11U) << d;
      const std::vector<geometry::Point> points =
          is_green ? std::vector<geometry::Point>{{v[0], v[1]},
                                                  {v[7], v[8]},
                                                  {v[9], v[10]},
                                                  {v[16], v[17]}}
                   : std::vector<geometry::Point>{{v[0], v[1]}, {v[2], v[3]}, {v[9], v[10]}};
      // The vertices' mean lies inside a 45° ring sector or a quarter disk: its cell is the path's.
      geometry::Point mean;
      for (const geometry::Point& p : points) {
        mean.x += (p.x - 0.15 * kSide) / kSide / static_cast<double>(points.size());
        mean.y += (p.y - 0.15 * kSide) / kSide / static_cast<double>(points.size());
      }
      const geometry::CellAt cell = geometry::LocateCell(mean.x, mean.y);
      const std::string where = "key " + std::to_string(value) + " " + d;
      ASSERT_EQ(cell.region, is_green ? geometry::Region::kGreen : geometry::Region::kRed) << where;
      // The outer arc runs clockwise through the cell's own 45° or 90° on the element's circle.
      const geometry::Point c = geometry::kElementCentres[cell.element];
      const geometry::Point from = points[is_green ? 0 : 1];
      const geometry::Point to = points[is_green ? 1 : 2];
      const double a0 =
          geometry::AngleOf(from.x - (0.15 + c.x) * kSide, from.y - (0.15 + c.y) * kSide);
      const double a1 = geometry::AngleOf(to.x - (0.15 + c.x) * kSide, to.y - (0.15 + c.y) * kSide);
      const double span = is_green ? 45.0 : 90.0;
      EXPECT_NEAR(std::fmod(a1 - a0 + 360.0, 360.0), span, 0.01) << where;
      EXPECT_NEAR(std::fmod(a0 + 360.0 - span * cell.index + 0.005, 360.0), 0.005, 0.01) << where;
      const double radius = is_green ? geometry::kGreenOuterRadius : geometry::kRedRadius;
      EXPECT_NEAR(v[is_green ? 2 : 4], radius * kSide, 1e-3) << where;
      EXPECT_EQ(v[is_green ? 5 : 7], 0) << where;  // the short way round,
      EXPECT_EQ(v[is_green ? 6 : 8], 1) << where;  // clockwise
      EXPECT_NEAR(std::hypot(to.x - (0.15 + c.x) * kSide, to.y - (0.15 + c.y) * kSide),
                  radius * kSide, 1e-3)
          << where;
      const bool bit =
          is_green ? cells.green[cell.element][cell.index] : cells.red[cell.element][cell.index];
      const PaletteColour colour =
          is_green ? (bit ? PaletteColour::kGreenOne : PaletteColour::kGreenZero)
                   : (bit ? PaletteColour::kRedOne : PaletteColour::kRedZero);
      EXPECT_EQ((*it)[3], Hex(colour)) << where;
      ++(is_green ? green_seen[cell.element][cell.index] : red_seen[cell.element][cell.index]);
    }
    for (int e = 0; e < kElements; ++e) {
      for (int s = 0; s < kGreenSectors; ++s) EXPECT_EQ(green_seen[e][s], 1) << value << " C" << e;
      for (int q = 0; q < kRedQuadrants; ++q) EXPECT_EQ(red_seen[e][q], 1) << value << " C" << e;
    }
  }
  // Key 0: each cell once, plus each element's underlay (a disk of each bit-0 colour).
  const std::string zero = RenderTagSvg(TagKey(0));
  EXPECT_EQ(Count(zero, "fill=\"" + Hex(PaletteColour::kGreenZero) + "\""), 32 + 4);
  EXPECT_EQ(Count(zero, "fill=\"" + Hex(PaletteColour::kRedOne) + "\""), 9);
  EXPECT_EQ(Count(zero, "fill=\"" + Hex(PaletteColour::kRedZero) + "\""), 7 + 4);
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
