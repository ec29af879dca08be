#pragma once
// A look at an uploaded photo's bytes before anything is decoded: which format, the pixel size
// its header claims (JPEG, PNG), and whether the file is whole. The pixel limit is checked from
// this (JPEG, PNG, WebP; TIFF's size is checked by the loader), so a tiny file claiming
// 100000 × 100000 pixels is refused without allocating them; and a
// truncated JPEG or PNG is refused instead of being decoded with a grey or missing bottom (libjpeg
// only warns about a premature end, and the detector would then read a partial photo).

#include <cstdint>
#include <span>
#include <string>

namespace pintag::app {

struct ImageHeader {
  std::string format;  ///< "jpeg", "png", "tiff", "webp"; empty when not an image we read
  int width = 0;       ///< from the header; 0 when unknown (TIFF: the decoder checks)
  int height = 0;
  bool complete = true;  ///< false: truncated or malformed structure
  std::string problem;   ///< why not complete
};

/// JPEG: markers walked up to the first scan (SOFn gives the size), then an EOI must follow
/// (bytes after EOI are allowed). PNG: chunks walked from IHDR to IEND. WebP: the canvas size of
/// its first chunk (VP8X, VP8L or VP8), read before the decoder, which decodes at once.
ImageHeader InspectImage(std::span<const std::uint8_t> bytes);

}  // namespace pintag::app
