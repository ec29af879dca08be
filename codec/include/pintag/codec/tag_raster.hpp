#pragma once
// Draws a tag as an anti-aliased RGB raster. Sizes are the black square's side; the quiet zone is
// added around it, so the image is about 1.3 times larger.

#include "pintag/codec/rgb_image.hpp"
#include "pintag/codec/tag_key.hpp"

namespace pintag {

inline constexpr int kMinTagSquarePx = 64;

struct TagRasterOptions {
  int square_px = 256;  ///< side of the black square in pixels, at least kMinTagSquarePx
  int supersample = 4;  ///< sub-samples per pixel side for anti-aliasing (1 = none), 1 … 16
};

struct TagRaster {
  RgbImage image;            ///< square, quiet zone included
  int square_origin_px = 0;  ///< the black square spans [origin, origin + square_px) in x and y
  int square_px = 0;
};

/// The quiet zone in whole pixels for a square of `square_px`: ceil(0.15 × square_px).
int QuietZonePx(int square_px);

/// Precondition: options within the documented ranges (callers validate user input).
TagRaster RenderTagRaster(TagKey key, const TagRasterOptions& options = {});

}  // namespace pintag
