// Photo bytes as /detect takes them: the header check, the decoder, then the whole detector.
// Any input must end in an image or an error value: never a crash, a hang or a sanitizer report.

#include <cstddef>
#include <cstdint>
#include <span>

#include "app/image_header.hpp"
#include "pintag/detector/detector.hpp"
#include "pintag/detector/image_io.hpp"

namespace {
constexpr std::int64_t kMaxPixels = 1 << 20;  // as the server's limit, smaller to keep runs fast
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::uint8_t> bytes(data, size);
  const pintag::app::ImageHeader header = pintag::app::InspectImage(bytes);
  if (header.format.empty() || !header.complete) return 0;  // the server stops here too
  if (std::int64_t{header.width} * header.height > kMaxPixels) return 0;
  const pintag::LoadResult loaded = pintag::LoadImageBytes(bytes, kMaxPixels);
  if (!loaded.image) return 0;
  (void)pintag::Detector(pintag::DetectorOptions{}).detect(*loaded.image);
  return 0;
}
