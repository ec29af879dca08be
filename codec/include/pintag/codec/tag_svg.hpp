#pragma once
// Draws a tag as SVG vector shapes: one path per cell, exact in the unit asked for.

#include <string>
#include <string_view>

#include "pintag/codec/tag_key.hpp"

namespace pintag {

struct TagSvgOptions {
  double square_side = 50;       ///< the black square's side in `unit`
  std::string_view unit = "mm";  ///< "mm" or "px"; sets the document's width/height unit
};

/// A standalone SVG document: quiet zone, black square, 32 green sectors and 16 red quadrants.
std::string RenderTagSvg(TagKey key, const TagSvgOptions& options = {});

}  // namespace pintag
