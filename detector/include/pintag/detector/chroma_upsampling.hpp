#pragma once
// How a photo's colour reached its BGR pixels. A JPEG (and a lossy WebP) usually stores Cb and Cr
// at half resolution, and its decoder interpolates them back up; the model reader undoes that
// interpolation to see the colour the file stores, and must not "undo" it where it never happened.

#include <cstdint>
#include <string_view>

namespace pintag {

/// The decoder's chroma interpolation, in the orientation of the decoded (upright) image.
enum class ChromaUpsampling : std::uint8_t {
  kNone,    ///< colour at full resolution (4:4:4, greyscale, PNG, TIFF, lossless WebP), or a
            ///< subsampling the reader does not model (4:1:1, scaled JPEG decoding): left as it is
  kBoth,    ///< 4:2:0: half resolution each way, triangle-interpolated (libjpeg's and libwebp's
            ///< default "fancy" upsampling). What phones save.
  kAcross,  ///< 4:2:2: half resolution across only (4:4:0 after a quarter turn)
  kDown,    ///< 4:4:0: half resolution down only (4:2:2 after a quarter turn)
};

/// "none", "4:2:0", "4:2:2" or "4:4:0" (the detect API's `image.chroma_upsampling`).
std::string_view ToString(ChromaUpsampling upsampling);

}  // namespace pintag
