#pragma once
// A plain 8-bit RGB raster: the renderer's output, independent of any imaging library.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "pintag/codec/cielab.hpp"

namespace pintag {

struct RgbImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;  ///< row-major, 3 bytes per pixel, no padding

  RgbImage() = default;
  RgbImage(int w, int h, Rgb8 fill = {255, 255, 255});

  Rgb8 at(int x, int y) const {
    const std::size_t i = (static_cast<std::size_t>(y) * width + x) * 3;
    return {pixels[i], pixels[i + 1], pixels[i + 2]};
  }
  void set(int x, int y, Rgb8 colour) {
    const std::size_t i = (static_cast<std::size_t>(y) * width + x) * 3;
    pixels[i] = colour.r;
    pixels[i + 1] = colour.g;
    pixels[i + 2] = colour.b;
  }
};

}  // namespace pintag
