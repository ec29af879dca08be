#pragma once
// Photo bytes -> pixels through OpenImageIO (JPEG, PNG, TIFF, WebP), EXIF orientation applied,
// EXIF focal length kept. The size in the header is checked before any pixel is decoded.

#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <span>
#include <string>

#include "pintag/detector/options.hpp"

namespace pintag {

inline constexpr std::int64_t kDefaultMaxPixels = 40'000'000;  ///< 40 MP

struct LoadedImage {
  cv::Mat bgr;  ///< CV_8UC3, upright (EXIF orientation applied)
  ExifCamera exif;
  int exif_orientation = 1;  ///< as found in the file, 1 … 8
  std::string format;        ///< OpenImageIO format name, e.g. "jpeg"
};

struct LoadResult {
  std::optional<LoadedImage> image;  ///< set on success
  std::string error;                 ///< why not, on failure
};

LoadResult LoadImageBytes(std::span<const std::uint8_t> bytes,
                          std::int64_t max_pixels = kDefaultMaxPixels);
LoadResult LoadImageFile(const std::string& path, std::int64_t max_pixels = kDefaultMaxPixels);

}  // namespace pintag
