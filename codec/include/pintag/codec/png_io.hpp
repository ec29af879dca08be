#pragma once
// PNG output through OpenImageIO, with the print resolution recorded in the file.

#include <cstdint>
#include <string>
#include <vector>

#include "pintag/codec/rgb_image.hpp"

namespace pintag {

/// Encodes as PNG with `dpi` pixels per inch recorded (pHYs). Returns empty bytes and sets
/// `error` when encoding fails.
std::vector<std::uint8_t> EncodePng(const RgbImage& image, double dpi, std::string* error);

/// Writes a PNG file; returns false and sets `error` (with the path and reason) on failure, a full
/// disk included.
bool WritePng(const RgbImage& image, const std::string& path, double dpi, std::string* error);

}  // namespace pintag
