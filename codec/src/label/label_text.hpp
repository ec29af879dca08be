#pragma once
// Text handling for labels: untrusted UTF-8 made safe to draw, and lines fitted to a width.

#include <string_view>

#include "label/label_font.hpp"
#include "label/label_utf8.hpp"

namespace pintag::label {

enum class Align { kLeft, kCentre, kRight };

struct LineStyle {
  bool bold = false;
  double size = 3;      ///< preferred font size, user units (mm on labels)
  double min_size = 2;  ///< shrink no further than this, then ellipsize
  Align align = Align::kLeft;
};

/// Draws one line of sanitized text with its baseline at `baseline`, inside [x, x + width]:
/// shrinks the font down to style.min_size to fit, then cuts whole characters (as a reader
/// counts them) from the end and appends "…". Returns the font size used.
double DrawLine(LabelFont& font, std::string_view text, double x, double width, double baseline,
                const LineStyle& style);

}  // namespace pintag::label
