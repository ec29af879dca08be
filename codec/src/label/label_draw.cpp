#include "label/label_draw.hpp"

#include <algorithm>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "label/label_text.hpp"
#include "pintag/codec/cells.hpp"
#include "pintag/codec/geometry.hpp"
#include "pintag/codec/palette.hpp"

namespace pintag::label {
namespace {

constexpr double kPadMm = 2.0;         // text inset from the rules
constexpr double kCaptionMm = 2.4;     // font size of "PIN CODE", "SORT BIN"
constexpr double kSmallPrintMm = 2.2;  // font size of the key line
constexpr double kMinNameMm = 2.2;     // names shrink to this, then ellipsize
constexpr double kGutterMm = 1.8;      // between the bin and the small print beside it
constexpr double kCaptionGapMm = 0.8;  // from a caption's baseline to the ink below it

void SetColour(cairo_t* cr, PaletteColour colour) {
  const Rgb8 c = SrgbFor(colour);
  cairo_set_source_rgb(cr, c.r / 255.0, c.g / 255.0, c.b / 255.0);
}

// Cairo measures angles from +x towards +y (clockwise on a y-down page); the format measures them
// clockwise from up.
double CairoAngle(double degrees_from_up) {
  return (degrees_from_up - 90.0) * std::numbers::pi / 180.0;
}

void Rule(cairo_t* cr, double x0, double y0, double x1, double y1) {
  cairo_move_to(cr, x0, y0);
  cairo_line_to(cr, x1, y1);
  cairo_stroke(cr);
}

// Ink height of a digit at font size 1: scales the pincode to its box.
double DigitHeightPerSize(LabelFont& font) {
  constexpr double kSize = 16.0;
  return font.measure("0", true, kSize).ink_height / kSize;
}

void DrawPin(LabelFont& font, const LabelContent& label, const Box& box) {
  font.show("PIN CODE", true, kCaptionMm, box.x + kPadMm, box.y + kPadMm + kCaptionMm * 0.75);

  // Written as India Post prints it, "110 001"; the digits fill the box below the caption.
  const std::string digits = label.pincode.str();
  const std::string text = digits.substr(0, 3) + " " + digits.substr(3);
  const double top = box.y + kPadMm + kCaptionMm + 1.0;
  const double height = box.bottom() - kPadMm - top;
  const double width = box.w - 4 * kPadMm;
  double size = height * 0.88 / DigitHeightPerSize(font);
  TextExtents e = font.measure(text, true, size);
  if (e.ink_width > width) {
    size *= width / e.ink_width;
    e = font.measure(text, true, size);
  }
  // Centre the ink, not the advance box, so the digits sit visually centred.
  const double x = box.x + (box.w - e.ink_width) / 2 - e.ink_x;
  const double y = top + (height - e.ink_height) / 2 - e.ink_y;
  font.show(text, true, size, x, y);
}

// A name as drawn: sanitized, and ending in "…" when it was longer than a label draws, so that
// the cut shows (a bin is never cut: DrawBin refuses it).
std::string NameText(std::string_view text) {
  bool cut = false;
  std::string name = SanitizeUtf8(text, &cut);
  if (cut) name += "\u2026";
  return name;
}

struct TextLine {
  std::string text;
  double size;
  bool bold;
};

// The office on one line when it fits at 3/4 of the preferred size or more, else on two lines of
// one size, broken at the space that makes the longer line shortest: filling the first line
// greedily left the second to shrink alone and be cut, though balanced lines held the whole name
// at one size. When even the balanced lines are too long at the smallest size, the first line
// takes as many words as fit there and the second is ellipsized.
void AddOfficeLines(LabelFont& font, const std::string& office, double width, double size,
                    double two_line_size, std::vector<TextLine>& lines) {
  const double fit = width / std::max(font.advancePerSize(office, true), 1e-9);
  if (fit >= 0.75 * size || office.find(' ') == std::string::npos) {
    lines.push_back({office, size, true});
    return;
  }
  std::size_t cut = office.find(' ');
  double longer = std::numeric_limits<double>::infinity();
  for (std::size_t at = cut; at != std::string::npos; at = office.find(' ', at + 1)) {
    const double advance = std::max(font.advancePerSize(office.substr(0, at), true),
                                    font.advancePerSize(office.substr(at + 1), true));
    if (advance < longer) {
      longer = advance;
      cut = at;
    }
  }
  // Just under the size that fits, so DrawLine does not shrink either line on its own.
  double common = std::min(two_line_size, width / std::max(longer, 1e-9) * 0.999);
  if (common < kMinNameMm) {
    common = kMinNameMm;
    cut = office.find(' ');
    for (std::size_t next = cut; next != std::string::npos; next = office.find(' ', next + 1)) {
      if (font.advancePerSize(office.substr(0, next), true) * common > width) break;
      cut = next;
    }
  }
  lines.push_back({office.substr(0, cut), common, true});
  lines.push_back({office.substr(cut + 1), common, true});
}

void DrawAddress(LabelFont& font, const LabelContent& label, const Box& box) {
  const double width = box.w - 2 * kPadMm;
  const double office_size = std::min(box.h * 0.36, 7.0);
  const double line2_size = std::min(box.h * 0.24, 4.6);
  const double two_line_size = std::max(
      kMinNameMm, std::min(0.75 * office_size, (box.h - 1.2 * line2_size - 2 * kPadMm) / 2.4));

  std::vector<TextLine> lines;
  const std::string office = NameText(label.office);
  AddOfficeLines(font, office.empty() ? std::string("\u2014") : office, width, office_size,
                 two_line_size, lines);
  const std::string district = NameText(label.district);
  const std::string state = NameText(label.state);
  std::string place = district;
  if (!district.empty() && !state.empty()) place += ", ";
  place += state;
  if (!place.empty()) lines.push_back({place, line2_size, false});

  // Spread the lines evenly; each takes its size in height (cap height plus descender, roughly).
  double total = 0;
  for (const TextLine& line : lines) total += line.size;
  const double gap = (box.h - total) / static_cast<double>(lines.size() + 1);
  double top = box.y + gap;
  for (const TextLine& line : lines) {
    DrawLine(font, line.text, box.x + kPadMm, width, top + line.size * 0.76,
             {.bold = line.bold,
              .size = line.size,
              .min_size = kMinNameMm,
              .align = Align::kLeft,
              .within = &box});
    top += line.size + gap;
  }
}

// Where a bin's name may go onto a second line: the first line is [0, first_end), the second
// starts at second_begin. `penalty` (1 or more) scales the longer line's length when breaks are
// compared, so a space wins over punctuation that balances the lines about as well.
struct LineBreak {
  std::size_t first_end;
  std::size_t second_begin;
  double penalty;
};

// At a space (dropped) and after a '-', '_', '/', '.' or ':'; when there is neither, between any
// two characters as a reader counts them ("CHUTE12" must still show its number; a vowel sign or
// a combining mark stays with its letter).
std::vector<LineBreak> BinBreaks(LabelFont& font, const std::string& bin) {
  constexpr double kPunctuationPenalty = 1.15;
  std::vector<LineBreak> breaks;
  for (std::size_t i = 0; i + 1 < bin.size(); ++i) {
    if (bin[i] == ' ') {
      breaks.push_back({i, i + 1, 1.0});
    } else if (std::string_view("-_/.:").find(bin[i]) != std::string_view::npos &&
               bin[i + 1] != ' ') {
      breaks.push_back({i + 1, i + 1, kPunctuationPenalty});
    }
  }
  if (!breaks.empty()) return breaks;
  for (const std::size_t i : font.cutPoints(bin)) {
    if (i > 0 && i < bin.size()) breaks.push_back({i, i, 1.0});
  }
  return breaks;
}

// The break whose longer line is shortest, between any two characters as a reader counts them
// (a space there is dropped), and that line's advance at size 1.
std::pair<LineBreak, double> ShortestBreak(LabelFont& font, const std::string& bin) {
  LineBreak cut{bin.size(), bin.size(), 1.0};
  double longer = std::numeric_limits<double>::infinity();
  for (const std::size_t i : font.cutPoints(bin)) {
    if (i == 0 || i >= bin.size()) continue;
    std::size_t first_end = i;
    std::size_t second_begin = i;
    while (first_end > 0 && bin[first_end - 1] == ' ') --first_end;
    while (second_begin < bin.size() && bin[second_begin] == ' ') ++second_begin;
    if (first_end == 0 || second_begin == bin.size()) continue;
    const double advance = std::max(font.advancePerSize(bin.substr(0, first_end), true),
                                    font.advancePerSize(bin.substr(second_begin), true));
    if (advance < longer) {
      longer = advance;
      cut = {first_end, second_begin, 1.0};
    }
  }
  return {cut, longer};
}

// A bin of many words too long for two lines at the 2.2 mm floor (64 bytes of capitals such as
// "MUMBAI WAREHOUSE WEST MEZZANINE WING DOCK …" on 100 x 150 mm), on three lines of one size,
// broken at spaces or punctuation where the longest line is shortest. Whether the lines were drawn
// whole; nothing, with nothing drawn, when no such breaks let three lines fit at the floor in
// `box`.
std::optional<bool> DrawBinOnThreeLines(LabelFont& font, const std::string& bin, const Box& box,
                                        double x, double width, double baseline, double size,
                                        double height) {
  // A space (dropped) or punctuation (a penalty): not BinBreaks' fallback between any two
  // characters, which it gives only for a bin with neither.
  std::vector<LineBreak> breaks;
  for (const LineBreak& at : BinBreaks(font, bin)) {
    if (at.penalty > 1.0 || bin[at.first_end] == ' ') breaks.push_back(at);
  }
  const auto advance = [&](std::size_t begin, std::size_t end) {
    return font.advancePerSize(bin.substr(begin, end - begin), true);
  };
  // The first and last lines measured once a break; the middle only for pairs that could still
  // win (a bin of many short words has hundreds of pairs, each measure a Pango layout).
  std::vector<double> first_line;
  std::vector<double> last_line;
  for (const LineBreak& at : breaks) {
    first_line.push_back(advance(0, at.first_end));
    last_line.push_back(advance(at.second_begin, bin.size()));
  }
  std::optional<std::pair<LineBreak, LineBreak>> best;
  double best_score = std::numeric_limits<double>::infinity();
  double longest = 0;
  for (std::size_t i = 0; i < breaks.size(); ++i) {
    for (std::size_t j = i + 1; j < breaks.size(); ++j) {
      const LineBreak& a = breaks[i];
      const LineBreak& b = breaks[j];
      if (b.first_end <= a.second_begin) continue;
      const double penalty = std::max(a.penalty, b.penalty);
      const double outer = std::max(first_line[i], last_line[j]);
      if (outer * penalty >= best_score) continue;
      const double line = std::max(outer, advance(a.second_begin, b.first_end));
      const double score = line * penalty;
      if (score < best_score) {
        best_score = score;
        longest = line;
        best = {a, b};
      }
    }
  }
  if (!best) return std::nullopt;
  const std::string lines[] = {
      bin.substr(0, best->first.first_end),
      bin.substr(best->first.second_begin, best->second.first_end - best->first.second_begin),
      bin.substr(best->second.second_begin)};
  // The top line's ink top, in sizes above the lowest baseline (1.12 sizes between the lines).
  constexpr double kMeasureMm = 16;
  const double above = 2.24 - font.measure(lines[0], true, kMeasureMm).ink_y / kMeasureMm;
  const double fitted = std::min(
      {size * 0.45, height / 3.4, width / std::max(longest, 1e-9), (baseline - box.y) / above});
  if (fitted < kMinNameMm) return std::nullopt;
  const LineStyle style{.bold = true, .size = fitted, .min_size = kMinNameMm, .within = &box};
  bool whole = true;
  for (int k = 0; k < 3; ++k) {
    whole =
        !DrawLine(font, lines[k], x, width, baseline - style.size * 1.12 * (2 - k), style).cut &&
        whole;
  }
  return whole;
}

// The bin on one line when it fits at 3 mm or more, else on two of one size, broken where the
// longer line is shortest: the end of a bin name ("… chute 12") is as much the answer as its
// start, so it is not cut off while a break can show it. When the preferred breaks (a space,
// punctuation) leave a line too long at the 2.2 mm floor, three lines broken at them are taken if
// they fit (DrawBinOnThreeLines), else any break between two characters that fits. When none fits,
// the second line keeps the longest end that fits and the first is ellipsized, and the caller
// refuses the label. The ink is clipped to `box`; marks stacked above the letters ("ǺỖ") make the
// size smaller, down to the 2.2 mm floor, so that they stay in it whole rather than clipped.
/// Draws `bin` on one, two or three lines; false when it was not drawn whole (a line was
/// ellipsized).
bool DrawBinValue(LabelFont& font, const std::string& bin, const Box& box, double x, double width,
                  double baseline, double size, double height) {
  constexpr double kOneLineMinMm = 3.0;
  const std::vector<LineBreak> breaks = BinBreaks(font, bin);
  if (font.advancePerSize(bin, true) * kOneLineMinMm <= width || breaks.empty()) {
    const double above = -font.measure(bin, true, size).ink_y;
    if (above > baseline - box.y) size = std::max(size * (baseline - box.y) / above, kMinNameMm);
    return !DrawLine(font, bin, x, width, baseline,
                     {.bold = true, .size = size, .min_size = kMinNameMm, .within = &box})
                .cut;
  }
  LineBreak cut = breaks.front();
  double longer = std::numeric_limits<double>::infinity();
  double best = std::numeric_limits<double>::infinity();
  for (const LineBreak& at : breaks) {
    const double advance = std::max(font.advancePerSize(bin.substr(0, at.first_end), true),
                                    font.advancePerSize(bin.substr(at.second_begin), true));
    if (advance * at.penalty < best) {
      best = advance * at.penalty;
      longer = advance;
      cut = at;
    }
  }
  // Three lines broken between words before two broken inside one ("…-MEZ / ZANINE-…").
  if (longer * kMinNameMm > width) {
    if (const auto drawn = DrawBinOnThreeLines(font, bin, box, x, width, baseline, size, height)) {
      return *drawn;
    }
    const auto [shortest, advance] = ShortestBreak(font, bin);
    if (advance < longer) {
      cut = shortest;
      longer = advance;
    }
  }
  if (longer * kMinNameMm > width) {
    // The longest end that fits on the second line, starting at a character (not a space, a
    // vowel sign or a combining mark).
    for (const std::size_t i : font.cutPoints(bin)) {
      if (i == 0 || i >= bin.size() || bin[i] == ' ') continue;
      if (font.advancePerSize(bin.substr(i), true) * kMinNameMm <= width) {
        cut = {i, i, 1.0};
        break;
      }
    }
    longer = width / kMinNameMm;
  }
  double fitted = std::min({size * 0.62, height / 2.3, width / std::max(longer, 1e-9)});
  // The first line's ink top, in sizes above the lower baseline (1.12 sizes between the lines).
  constexpr double kMeasureMm = 16;
  const double above =
      1.12 - font.measure(bin.substr(0, cut.first_end), true, kMeasureMm).ink_y / kMeasureMm;
  fitted = std::min(fitted, (baseline - box.y) / above);
  const LineStyle style{
      .bold = true, .size = std::max(fitted, kMinNameMm), .min_size = kMinNameMm, .within = &box};
  // Whole when neither line was ellipsized as drawn (measured at the size drawn, not predicted).
  const bool first_cut =
      DrawLine(font, bin.substr(0, cut.first_end), x, width, baseline - style.size * 1.12, style)
          .cut;
  const bool second_cut =
      DrawLine(font, bin.substr(cut.second_begin), x, width, baseline, style).cut;
  return !first_cut && !second_cut;
}

// A bin cut short can read as another bin of the plan ("Kolkata…Bay 12" for Inbound and
// Outbound alike), and the bin is what a sorter acts on: no label rather than a wrong one.
std::string UnprintableBinReason(const LabelContent& label) {
  return "the sort bin '" + SanitizeUtf8(*label.bin) + "' of pincode " + label.pincode.str() +
         " is too long to print whole on this label size, even on two or three lines at the "
         "smallest "
         "print, and a bin cut short could read as another; print a larger label, or give the "
         "bin a shorter name in its plan";
}

/// False when the bin could not be printed whole (DrawBinValue).
bool DrawBin(LabelFont& font, const LabelContent& label, const Box& box) {
  const double caption_baseline = box.y + kPadMm + kCaptionMm * 0.75;
  font.show("SORT BIN", true, kCaptionMm, box.x + kPadMm, caption_baseline);

  // The bin value big on the left half; the plan and the key in small print on the right, a
  // gutter between (the bin's last letter touched "key 4321" on 70 x 50 mm).
  const double value_top = box.y + kPadMm + kCaptionMm + 0.8;
  const double value_h = box.bottom() - kPadMm - value_top;
  const double value_size = std::min(value_h * 1.05, 14.0);
  const double divide = box.x + box.w * 0.58;  // the gutter's middle
  const double left_w = divide - kGutterMm / 2 - box.x - kPadMm;
  // The bin's ink stays below the caption's baseline (a tilde over "Ỗ" ran through its N) and
  // left of the gutter's middle.
  const Box value_box{box.x, caption_baseline + kCaptionGapMm, divide - box.x,
                      box.bottom() - caption_baseline - kCaptionGapMm};
  bool cut = false;
  const std::string bin = label.bin ? SanitizeUtf8(*label.bin, &cut) : std::string();
  // Cut to the drawn length, a bin would print short, as a bin cut to fit would: refused alike.
  bool whole = !cut;
  if (bin.empty()) {
    // No plan chosen (or the plan has no bin for this pincode): say so quietly.
    DrawLine(font, "none", box.x + kPadMm, left_w, box.bottom() - kPadMm - value_h * 0.08,
             {.bold = false, .size = std::min(value_size, 5.0), .min_size = 2.0});
  } else {
    whole = DrawBinValue(font, bin, value_box, box.x + kPadMm, left_w,
                         box.bottom() - kPadMm - value_h * 0.08, value_size, value_h) &&
            whole;
  }

  const double right_x = divide + kGutterMm / 2;
  const double right_w = box.right() - kPadMm - right_x;
  if (label.plan) {
    const std::string plan = NameText(*label.plan);
    if (!plan.empty()) {
      // Cut from the middle: plans are often named alike at the start ("mumbai-central-inbound",
      // "mumbai-central-outbound"), and cut at the end they printed alike.
      static constexpr std::string_view kPlanPrefix = "plan ";
      DrawLine(font, std::string(kPlanPrefix) + plan, right_x, right_w,
               box.y + kPadMm + kCaptionMm * 0.75,
               {.bold = false,
                .size = kCaptionMm,
                .min_size = 1.8,
                .align = Align::kRight,
                .cut_middle = true,
                .uncut_prefix = kPlanPrefix.size(),
                .within = &box});
    }
  }
  // Down to 1.4 mm, as the line under it: the gutter left "key 12345" 7.9 mm on 70 x 50 mm, too
  // little at 1.6 mm, and a key must print whole.
  DrawLine(font, "key " + std::to_string(label.key.value()), right_x, right_w,
           box.bottom() - kPadMm - kSmallPrintMm * 1.2,
           {.bold = false, .size = kSmallPrintMm, .min_size = 1.4, .align = Align::kRight});
  DrawLine(font, "PinTag v1", right_x, right_w, box.bottom() - kPadMm,
           {.bold = false, .size = kSmallPrintMm * 0.85, .min_size = 1.4, .align = Align::kRight});
  return whole;
}

}  // namespace

void DrawTagVector(cairo_t* cr, TagKey key, const LabelTagPlacement& placement) {
  const TagCells cells = EncodeCells(key);
  const double s = placement.square_side_mm;
  const double x0 = placement.square_x_mm;
  const double y0 = placement.square_y_mm;
  const double quiet = geometry::kQuietZone * s;

  cairo_save(cr);
  cairo_new_path(cr);
  SetColour(cr, PaletteColour::kWhite);
  cairo_rectangle(cr, x0 - quiet, y0 - quiet, s + 2 * quiet, s + 2 * quiet);
  cairo_fill(cr);
  SetColour(cr, PaletteColour::kBlack);
  cairo_rectangle(cr, x0, y0, s, s);
  cairo_fill(cr);

  const double r_red = geometry::kRedRadius * s;
  const double r_green = geometry::kGreenOuterRadius * s;
  for (int e = 0; e < kElements; ++e) {
    const double cx = x0 + geometry::kElementCentres[e].x * s;
    const double cy = y0 + geometry::kElementCentres[e].y * s;
    // An underlay in the bit-0 colours, exactly the ring's and disk's outlines: where a viewer
    // anti-aliases the seams between adjacent cells, it blends with a palette colour instead of
    // showing the black square through as hairlines. Printers do not anti-alias; nothing changes.
    cairo_new_path(cr);
    cairo_arc(cr, cx, cy, r_green, 0, 2 * std::numbers::pi);
    cairo_new_sub_path(cr);
    cairo_arc_negative(cr, cx, cy, r_red, 2 * std::numbers::pi, 0);
    SetColour(cr, PaletteColour::kGreenZero);
    cairo_fill(cr);
    cairo_arc(cr, cx, cy, r_red, 0, 2 * std::numbers::pi);
    SetColour(cr, PaletteColour::kRedZero);
    cairo_fill(cr);
    for (int sector = 0; sector < kGreenSectors; ++sector) {
      const double from = CairoAngle(45.0 * sector);
      const double to = CairoAngle(45.0 * (sector + 1));
      cairo_new_path(cr);
      cairo_arc(cr, cx, cy, r_green, from, to);
      cairo_arc_negative(cr, cx, cy, r_red, to, from);
      cairo_close_path(cr);
      SetColour(cr, cells.green[e][sector] ? PaletteColour::kGreenOne : PaletteColour::kGreenZero);
      cairo_fill(cr);
    }
    for (int quadrant = 0; quadrant < kRedQuadrants; ++quadrant) {
      cairo_new_path(cr);
      cairo_move_to(cr, cx, cy);
      cairo_arc(cr, cx, cy, r_red, CairoAngle(90.0 * quadrant), CairoAngle(90.0 * (quadrant + 1)));
      cairo_close_path(cr);
      SetColour(cr, cells.red[e][quadrant] ? PaletteColour::kRedOne : PaletteColour::kRedZero);
      cairo_fill(cr);
    }
  }
  cairo_restore(cr);
}

std::string DrawLabel(cairo_t* cr, const LabelContent& label, const LabelLayout& layout,
                      bool with_tag) {
  cairo_save(cr);
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);

  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_set_line_width(cr, layout.rule_mm);
  const Box& f = layout.frame;
  cairo_rectangle(cr, f.x, f.y, f.w, f.h);
  cairo_stroke(cr);
  Rule(cr, layout.pin.x, layout.pin.bottom(), layout.pin.right(), layout.pin.bottom());
  Rule(cr, layout.address.x, layout.address.bottom(), layout.address.right(),
       layout.address.bottom());
  if (layout.landscape) {
    Rule(cr, layout.tag.right(), f.y, layout.tag.right(), f.bottom());
  } else {
    Rule(cr, layout.bin.x, layout.bin.y, layout.bin.right(), layout.bin.y);
  }

  LabelFont font(cr);
  DrawPin(font, label, layout.pin);
  DrawAddress(font, label, layout.address);
  const bool bin_whole = DrawBin(font, label, layout.bin);
  cairo_restore(cr);

  if (with_tag) DrawTagVector(cr, label.key, layout.placement);
  return bin_whole ? std::string() : UnprintableBinReason(label);
}

std::string BinRefusal(cairo_t* cr, const LabelContent& label, const LabelLayout& layout) {
  cairo_save(cr);
  LabelFont font(cr);
  const bool whole = DrawBin(font, label, layout.bin);
  cairo_restore(cr);
  return whole ? std::string() : UnprintableBinReason(label);
}

}  // namespace pintag::label
