#pragma once
// Draws a label onto any cairo surface whose user space is millimetres from the page's top-left.

#include <cairo.h>

#include <string>

#include "label/label_layout.hpp"
#include "pintag/codec/label.hpp"

namespace pintag::label {

/// The tag as vector paths at `placement`: white quiet zone, black square, 32 green sectors and
/// 16 red quadrants, from codec geometry and palette.
void DrawTagVector(cairo_t* cr, TagKey key, const LabelTagPlacement& placement);

/// Everything but the tag when `with_tag` is false (the raster renderer pastes the codec's own
/// anti-aliased tag raster instead). Empty, or why the label must not be printed: its sort bin
/// did not fit whole (what was drawn is to be thrown away).
std::string DrawLabel(cairo_t* cr, const LabelContent& label, const LabelLayout& layout,
                      bool with_tag);

/// DrawLabel's refusal of `label` for its sort bin, found by drawing the bin box alone on `cr`, a
/// surface that is thrown away: empty when the bin prints whole on `layout`.
std::string BinRefusal(cairo_t* cr, const LabelContent& label, const LabelLayout& layout);

}  // namespace pintag::label
