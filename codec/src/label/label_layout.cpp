#include "label/label_layout.hpp"

#include <algorithm>

#include "pintag/codec/geometry.hpp"

namespace pintag::label {
namespace {

constexpr double kMarginMm = 3;           // printers rarely print the outermost 2 mm reliably
constexpr double kRuleMm = 0.5;           // frame and divider lines
constexpr double kTagPadMm = 1.0;         // between the quiet zone's edge and the nearest rule
constexpr double kLandscapeAspect = 1.4;  // wider than this: tag on the left, text on the right
// A text row's least height: its caption, two lines at the 2.2 mm floor of label_draw.cpp and
// the pads around them. Below it the rows' contents run into each other.
constexpr double kMinTextRowMm = 12;

void PlaceTag(LabelLayout& layout) {
  // The tag with its quiet zone, as large as the tag box allows, centred; the rules stay clear of
  // the quiet zone by half their width plus a pad.
  const double total = std::min(layout.tag.w, layout.tag.h) - kRuleMm - 2 * kTagPadMm;
  const double side = std::max(total, 0.0) / (1 + 2 * geometry::kQuietZone);
  layout.placement.square_side_mm = side;
  layout.placement.square_x_mm = layout.tag.x + (layout.tag.w - side) / 2;
  layout.placement.square_y_mm = layout.tag.y + (layout.tag.h - side) / 2;
}

}  // namespace

LabelLayout ComputeLayout(const LabelSize& size) {
  LabelLayout layout;
  layout.size = size;
  layout.rule_mm = kRuleMm;
  layout.frame = {kMarginMm, kMarginMm, size.width_mm - 2 * kMarginMm,
                  size.height_mm - 2 * kMarginMm};
  const Box& f = layout.frame;
  layout.landscape = size.width_mm >= kLandscapeAspect * size.height_mm;
  if (layout.landscape) {
    const double column = std::min(f.h, 0.6 * f.w);
    layout.tag = {f.x, f.y, column, f.h};
    const double tx = f.x + column;
    const double tw = f.w - column;
    const double pin_h = 0.38 * f.h;
    const double address_h = 0.34 * f.h;
    layout.pin = {tx, f.y, tw, pin_h};
    layout.address = {tx, f.y + pin_h, tw, address_h};
    layout.bin = {tx, f.y + pin_h + address_h, tw, f.h - pin_h - address_h};
  } else {
    const double pin_h = std::max(0.19 * f.h, kMinTextRowMm);
    const double address_h = std::max(0.15 * f.h, kMinTextRowMm);
    const double bin_h = std::max(0.12 * f.h, kMinTextRowMm);
    layout.pin = {f.x, f.y, f.w, pin_h};
    layout.address = {f.x, f.y + pin_h, f.w, address_h};
    layout.tag = {f.x, f.y + pin_h + address_h, f.w, f.h - pin_h - address_h - bin_h};
    layout.bin = {f.x, f.bottom() - bin_h, f.w, bin_h};
  }
  PlaceTag(layout);
  return layout;
}

}  // namespace pintag::label
