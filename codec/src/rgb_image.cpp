#include "pintag/codec/rgb_image.hpp"

namespace pintag {

RgbImage::RgbImage(int w, int h, Rgb8 fill)
    : width(w), height(h), pixels(static_cast<std::size_t>(w) * h * 3) {
  for (std::size_t i = 0; i < pixels.size(); i += 3) {
    pixels[i] = fill.r;
    pixels[i + 1] = fill.g;
    pixels[i + 2] = fill.b;
  }
}

}  // namespace pintag
