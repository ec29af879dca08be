#include "pintag/codec/tag_svg.hpp"

#include <cstdio>
#include <string>
#include <tuple>

#include "pintag/codec/cells.hpp"
#include "pintag/codec/geometry.hpp"
#include "pintag/codec/palette.hpp"

namespace pintag {
namespace {

std::string Hex(PaletteColour colour) {
  const Rgb8 c = SrgbFor(colour);
  char text[8];
  std::snprintf(text, sizeof text, "#%02x%02x%02x", c.r, c.g, c.b);
  return text;
}

// Numbers to 1/10000 of a unit: far below any printer's resolution, short in the file.
std::string Num(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4f", value);
  std::string s = text;
  while (s.back() == '0') s.pop_back();
  if (s.back() == '.') s.pop_back();
  return s == "-0" ? "0" : s;
}

struct Frame {
  double origin;  // the square's top-left corner in document units
  double side;    // the square's side in document units
  double x(double u) const { return origin + u * side; }
  double y(double v) const { return origin + v * side; }
};

std::string PointAt(const Frame& f, geometry::Point centre, double radius, double degrees) {
  const geometry::Point d = geometry::Direction(degrees);
  return Num(f.x(centre.x + radius * d.x)) + "," + Num(f.y(centre.y + radius * d.y));
}

// An annular wedge (green sector) between two angles; the sweep runs clockwise on screen.
std::string SectorPath(const Frame& f, geometry::Point c, double inner, double outer, double from,
                       double to) {
  const std::string ro = Num(outer * f.side);
  const std::string ri = Num(inner * f.side);
  // Appended piece by piece: GCC 12 warns falsely on "M" + std::string (its bug 105329).
  std::string path = "M";
  path += PointAt(f, c, outer, from) + " A" + ro + "," + ro + " 0 0 1 ";
  path += PointAt(f, c, outer, to) + " L" + PointAt(f, c, inner, to);
  path += " A" + ri + "," + ri + " 0 0 0 " + PointAt(f, c, inner, from) + " Z";
  return path;
}

// A pie wedge (red quadrant) from the element's centre.
std::string QuadrantPath(const Frame& f, geometry::Point c, double radius, double from, double to) {
  const std::string r = Num(radius * f.side);
  std::string path = "M";
  path += Num(f.x(c.x)) + "," + Num(f.y(c.y)) + " L" + PointAt(f, c, radius, from);
  path += " A" + r + "," + r + " 0 0 1 " + PointAt(f, c, radius, to) + " Z";
  return path;
}

}  // namespace

std::string RenderTagSvg(TagKey key, const TagSvgOptions& options) {
  const TagCells cells = EncodeCells(key);
  const Frame frame{geometry::kQuietZone * options.square_side, options.square_side};
  const double total = options.square_side * (1 + 2 * geometry::kQuietZone);
  const std::string unit(options.unit);

  std::string svg = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  svg += "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"" + Num(total) + unit +
         "\" height=\"" + Num(total) + unit + "\" viewBox=\"0 0 " + Num(total) + " " + Num(total) +
         "\" shape-rendering=\"geometricPrecision\">\n";
  svg += "  <title>PinTag v1 key " + std::to_string(key.value()) + "</title>\n";
  svg += "  <rect class=\"quiet-zone\" x=\"0\" y=\"0\" width=\"" + Num(total) + "\" height=\"" +
         Num(total) + "\" fill=\"" + Hex(PaletteColour::kWhite) + "\"/>\n";
  svg += "  <rect class=\"square\" x=\"" + Num(frame.origin) + "\" y=\"" + Num(frame.origin) +
         "\" width=\"" + Num(frame.side) + "\" height=\"" + Num(frame.side) + "\" fill=\"" +
         Hex(PaletteColour::kBlack) + "\"/>\n";
  for (int e = 0; e < kElements; ++e) {
    const geometry::Point c = geometry::kElementCentres[e];
    svg += "  <g class=\"element\" id=\"C" + std::to_string(e) + "\">\n";
    // An underlay in the bit-0 colours under the cells, exactly their outlines (as the label's
    // DrawTagVector has): a viewer that anti-aliases blends each seam between two cells with a
    // palette colour instead of the black square, which showed through as dark hairlines.
    const std::string r_green = Num(geometry::kGreenOuterRadius * frame.side);
    const std::string r_red = Num(geometry::kRedRadius * frame.side);
    const std::string cx = Num(frame.x(c.x));
    const std::string cy = Num(frame.y(c.y));
    for (const auto& [name, radius, colour] :
         {std::tuple{"green", r_green, PaletteColour::kGreenZero},
          std::tuple{"red", r_red, PaletteColour::kRedZero}}) {
      svg += "    <circle class=\"underlay ";
      svg += name;
      svg += "\" cx=\"" + cx;
      svg += "\" cy=\"" + cy;
      svg += "\" r=\"" + radius;
      svg += "\" fill=\"" + Hex(colour);
      svg += "\"/>\n";
    }
    for (int s = 0; s < kGreenSectors; ++s) {
      const PaletteColour colour =
          cells.green[e][s] ? PaletteColour::kGreenOne : PaletteColour::kGreenZero;
      svg += "    <path class=\"sector green\" d=\"" +
             SectorPath(frame, c, geometry::kRedRadius, geometry::kGreenOuterRadius, 45.0 * s,
                        45.0 * (s + 1)) +
             "\" fill=\"" + Hex(colour) + "\"/>\n";
    }
    for (int q = 0; q < kRedQuadrants; ++q) {
      const PaletteColour colour =
          cells.red[e][q] ? PaletteColour::kRedOne : PaletteColour::kRedZero;
      svg += "    <path class=\"sector red\" d=\"" +
             QuadrantPath(frame, c, geometry::kRedRadius, 90.0 * q, 90.0 * (q + 1)) + "\" fill=\"" +
             Hex(colour) + "\"/>\n";
    }
    svg += "  </g>\n";
  }
  svg += "</svg>\n";
  return svg;
}

}  // namespace pintag
