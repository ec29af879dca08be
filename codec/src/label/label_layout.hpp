#pragma once
// Where each part of a label goes, in millimetres from the page's top-left corner. Shared by the
// vector and raster renderers so all formats agree.

#include "pintag/codec/label.hpp"

namespace pintag::label {

struct Box {
  double x = 0;
  double y = 0;
  double w = 0;
  double h = 0;
  double right() const { return x + w; }
  double bottom() const { return y + h; }
};

struct LabelLayout {
  LabelSize size;
  bool landscape = false;  ///< tag in a left column, text stacked on the right
  double rule_mm = 0;      ///< width of the frame and divider lines
  Box frame;               ///< the outer border (stroked centred on this box)
  Box pin;                 ///< "PIN" caption and the six digits
  Box address;             ///< office, then district and state
  Box tag;                 ///< reserved for the tag with its quiet zone; no ink but the tag
  Box bin;                 ///< sort bin, plan and the key in small print
  LabelTagPlacement placement;
};

LabelLayout ComputeLayout(const LabelSize& size);

}  // namespace pintag::label
