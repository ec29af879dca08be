// Photo bytes as /detect takes them: the loader (format sniffed once, header size checked against
// the pixel limit before any decoder runs, truncation refused), then the whole detector.
// Any input must end in an image or an error value: never a crash, a hang or a sanitizer report.

#include <cstddef>
#include <cstdint>
#include <span>

#include "pintag/detector/detector.hpp"
#include "pintag/detector/image_io.hpp"

namespace {
constexpr std::int64_t kMaxPixels = 1 << 20;  // as the server's limit, smaller to keep runs fast
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::uint8_t> bytes(data, size);
  const pintag::LoadResult loaded = pintag::LoadImageBytes(bytes, kMaxPixels);
  if (!loaded.image) return 0;
  (void)pintag::Detector(pintag::DetectorOptions{}).detect(*loaded.image);
  return 0;
}
