#pragma once
// Photo bytes -> pixels. JPEG goes through libjpeg-turbo (TurboJPEG) directly; PNG, TIFF and WebP
// through OpenImageIO. EXIF orientation is applied and the EXIF focal length kept. The format is
// told from the first bytes once, and the size in the header is checked against the pixel limit
// before any pixel is decoded; a truncated JPEG or PNG is refused rather than decoded with a grey
// or missing bottom.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <opencv2/core.hpp>
#include <optional>
#include <span>
#include <string>

#include "pintag/detector/chroma_upsampling.hpp"
#include "pintag/detector/options.hpp"

namespace pintag {

inline constexpr std::int64_t kDefaultMaxPixels = 40'000'000;  ///< 40 MP
/// Most channels a photo may have (grey, grey and alpha, RGB, RGBA); more is
/// ImageError::kUnsupported, refused before decoding.
inline constexpr int kMaxChannels = 4;

/// Why a photo was not loaded: what an HTTP front end maps to 415, 413 and 400.
enum class ImageError {
  kNone,
  kUnsupported,  ///< not a JPEG, PNG, TIFF or WebP (or empty)
  kTooLarge,     ///< the header claims more pixels than allowed
  kCorrupt,      ///< truncated, malformed or undecodable
  kUnreadable,   ///< the file could not be opened (LoadImageFile)
};

/// "unsupported", "too_large", "corrupt", "unreadable" ("none" for kNone).
const char* ToString(ImageError error);

enum class ImageFormat { kUnknown, kJpeg, kPng, kTiff, kWebp };

/// From the first bytes alone; kUnknown for anything else.
/// How many first bytes SniffImageFormat needs to tell every format (a WebP's RIFF header is 12).
inline constexpr std::size_t kSniffImageBytes = 16;
ImageFormat SniffImageFormat(std::span<const std::uint8_t> bytes);

struct LoadOptions {
  std::int64_t max_pixels = kDefaultMaxPixels;  ///< limit on the stored (full-size) pixels
  /// JPEG only: decode at 1/scale_denominator of the size (1, 2, 4 or 8; libjpeg-turbo skips the
  /// work, it does not resize afterwards). Other formats ignore it and load at full size.
  int scale_denominator = 1;
  /// Called once, with the stored size the header claims, after that size passed `max_pixels` and
  /// right before any pixel is decoded; not called for a photo refused before that. A server
  /// waits here until its memory budget has room for the pixels (pintag serve
  /// --max-pixels-in-flight). Exceptions it throws pass to the caller.
  std::function<void(int width, int height)> before_decode;
};

struct LoadedImage {
  cv::Mat bgr;  ///< CV_8UC3, upright (EXIF orientation applied)
  ExifCamera exif;
  int exif_orientation = 1;  ///< as found in the file, 1 … 8
  std::string format;        ///< "jpeg", "png", "tiff" or "webp"
  /// How the decoder filled in colour the file stores at lower resolution (JPEG's subsampling,
  /// lossy WebP's 4:2:0), in the upright image's axes.
  ChromaUpsampling chroma_upsampling = ChromaUpsampling::kNone;
};

struct LoadResult {
  std::optional<LoadedImage> image;  ///< set on success
  ImageError kind = ImageError::kNone;
  std::string error;  ///< why not, on failure, for people
  /// The stored size the header claims (before orientation), when it was read: set for too-large
  /// images too, 0 when the header was not reached.
  int claimed_width = 0;
  int claimed_height = 0;
};

LoadResult LoadImageBytes(std::span<const std::uint8_t> bytes, const LoadOptions& options);
LoadResult LoadImageBytes(std::span<const std::uint8_t> bytes,
                          std::int64_t max_pixels = kDefaultMaxPixels);
/// A file of at most 1 GiB (a larger one, or a device that gives more, is kTooLarge unread).
LoadResult LoadImageFile(const std::string& path, std::int64_t max_pixels = kDefaultMaxPixels);
/// A photo read whole from `in` (standard input, a pipe), at most 1 GiB as LoadImageFile reads a
/// file; `name` ("standard input") begins its errors. `expected_bytes`, when known (a regular
/// file's size), is reserved at once.
LoadResult LoadImageStream(std::istream& in, const std::string& name,
                           std::int64_t max_pixels = kDefaultMaxPixels,
                           std::size_t expected_bytes = 0);

/// A JPEG's planes as stored, for a reader that wants full-resolution luma and the chroma at the
/// resolution the file kept (4:2:0 phones: half in each direction). Not reoriented.
struct JpegPlanes {
  cv::Mat y;   ///< CV_8UC1, full size
  cv::Mat cb;  ///< CV_8UC1, subsampled as stored
  cv::Mat cr;
  int orientation = 1;  ///< EXIF orientation, for the caller to apply
};

struct JpegPlanesResult {
  std::optional<JpegPlanes> planes;
  ImageError kind = ImageError::kNone;
  std::string error;
};

/// Greyscale JPEGs give empty cb and cr.
JpegPlanesResult LoadJpegPlanes(std::span<const std::uint8_t> bytes,
                                std::int64_t max_pixels = kDefaultMaxPixels);

}  // namespace pintag
