#pragma once
// Text handling for labels: untrusted UTF-8 made safe to draw, and lines fitted to a width.

#include <string_view>

#include "label/label_font.hpp"
#include "label/label_layout.hpp"
#include "label/label_utf8.hpp"

namespace pintag::label {

enum class Align { kLeft, kCentre, kRight };

struct LineStyle {
  bool bold = false;
  double size = 3;      ///< preferred font size, user units (mm on labels)
  double min_size = 2;  ///< shrink no further than this, then ellipsize
  Align align = Align::kLeft;
  /// Too long at min_size: cut from the middle ("mumbai-c…-inbound"), keeping both ends, rather
  /// than from the end. For names that differ at either end, such as a plan's.
  bool cut_middle = false;
  /// Bytes at the start never cut ("plan " before a plan's name): the cut shares out the rest.
  std::size_t uncut_prefix = 0;
  /// The box the line belongs to (its ink is clipped to it as well); none: only the line's band.
  const Box* within = nullptr;
};

/// Draws one line of sanitized text with its baseline at `baseline`, inside [x, x + width]:
/// shrinks the font down to style.min_size to fit, then cuts whole characters (as a reader
/// counts them) from the end, or the middle (style.cut_middle), for a "…". Returns the font size
/// used, and whether it cut. Ink is clipped to the line's band (1.3 sizes above the baseline, 0.6
/// below, a little either side of the width) and to style.within: a name of stacked combining
/// marks, which the API accepts, drew over the pincode digits and the bin instead of staying on its
/// row. Real text of every script the label prints stays inside the band.
struct DrawnLine {
  double size = 0;   ///< the font size used
  bool cut = false;  ///< characters were cut for an ellipsis
};
DrawnLine DrawLine(LabelFont& font, std::string_view text, double x, double width, double baseline,
                   const LineStyle& style);

}  // namespace pintag::label
