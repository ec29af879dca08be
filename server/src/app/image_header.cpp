#include "app/image_header.hpp"

#include <algorithm>
#include <cstring>

namespace pintag::app {
namespace {

std::uint32_t Be16(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 8) | p[1];
}
std::uint32_t Be32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         p[3];
}

ImageHeader Incomplete(ImageHeader header, std::string problem) {
  header.complete = false;
  header.problem = std::move(problem);
  return header;
}

ImageHeader InspectJpeg(std::span<const std::uint8_t> b) {
  ImageHeader h;
  h.format = "jpeg";
  std::size_t pos = 2;
  while (true) {
    while (pos < b.size() && b[pos] == 0xFF && pos + 1 < b.size() && b[pos + 1] == 0xFF) ++pos;
    if (pos + 2 > b.size()) return Incomplete(h, "the JPEG ends before its first scan");
    if (b[pos] != 0xFF) return Incomplete(h, "the JPEG's marker structure is broken");
    const std::uint8_t marker = b[pos + 1];
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) {
      pos += 2;
      continue;
    }
    if (marker == 0xD9) return Incomplete(h, "the JPEG ends before its first scan");
    if (pos + 4 > b.size()) return Incomplete(h, "the JPEG ends inside a segment header");
    const std::size_t length = Be16(&b[pos + 2]);
    if (length < 2 || pos + 2 + length > b.size())
      return Incomplete(h, "the JPEG ends inside a segment");
    const bool sof =
        marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (sof && length >= 7) {
      h.height = static_cast<int>(Be16(&b[pos + 5]));
      h.width = static_cast<int>(Be16(&b[pos + 7]));
    }
    pos += 2 + length;
    if (marker == 0xDA) break;  // start of scan: entropy-coded data follows
  }
  // In entropy-coded data a 0xFF byte is followed by 0x00 (stuffing), a restart marker or another
  // marker; FF D9 is the end of the image.
  static constexpr std::uint8_t kEoi[] = {0xFF, 0xD9};
  if (std::search(b.begin() + static_cast<std::ptrdiff_t>(pos), b.end(), std::begin(kEoi),
                  std::end(kEoi)) == b.end()) {
    return Incomplete(h, "the JPEG is truncated (no end-of-image marker)");
  }
  return h;
}

ImageHeader InspectPng(std::span<const std::uint8_t> b) {
  ImageHeader h;
  h.format = "png";
  std::size_t pos = 8;
  bool first = true;
  while (true) {
    if (pos + 12 > b.size()) return Incomplete(h, "the PNG is truncated (no IEND chunk)");
    const std::uint32_t length = Be32(&b[pos]);
    if (length > 0x7FFFFFFFu || pos + 12 + length > b.size())
      return Incomplete(h, "the PNG is truncated inside a chunk");
    const std::string type(reinterpret_cast<const char*>(&b[pos + 4]), 4);
    if (first) {
      if (type != "IHDR" || length < 8) return Incomplete(h, "the PNG does not start with IHDR");
      h.width = static_cast<int>(std::min<std::uint32_t>(Be32(&b[pos + 8]), 0x7FFFFFFF));
      h.height = static_cast<int>(std::min<std::uint32_t>(Be32(&b[pos + 12]), 0x7FFFFFFF));
      first = false;
    }
    if (type == "IEND") return h;
    pos += 12 + length;
  }
}

std::uint32_t Le24(const std::uint8_t* p) {
  return p[0] | (std::uint32_t{p[1]} << 8) | (std::uint32_t{p[2]} << 16);
}

/// The canvas size from the first chunk: VP8X (extended), VP8L (lossless) or "VP8 " (lossy).
ImageHeader InspectWebp(std::span<const std::uint8_t> b) {
  ImageHeader h;
  h.format = "webp";
  const auto chunk = [&](const char* fourcc) {
    return b.size() >= 16 && std::memcmp(b.data() + 12, fourcc, 4) == 0;
  };
  if (chunk("VP8X")) {
    if (b.size() < 30) return Incomplete(h, "truncated WebP header");
    h.width = static_cast<int>(Le24(b.data() + 24) + 1);
    h.height = static_cast<int>(Le24(b.data() + 27) + 1);
  } else if (chunk("VP8L")) {
    if (b.size() < 25 || b[20] != 0x2f) return Incomplete(h, "truncated WebP header");
    const std::uint32_t bits = b[21] | (std::uint32_t{b[22]} << 8) | (std::uint32_t{b[23]} << 16) |
                               (std::uint32_t{b[24]} << 24);
    h.width = static_cast<int>((bits & 0x3FFF) + 1);
    h.height = static_cast<int>(((bits >> 14) & 0x3FFF) + 1);
  } else if (chunk("VP8 ")) {
    if (b.size() < 30 || b[23] != 0x9d || b[24] != 0x01 || b[25] != 0x2a)
      return Incomplete(h, "truncated WebP header");
    h.width = static_cast<int>((b[26] | (b[27] << 8)) & 0x3FFF);
    h.height = static_cast<int>((b[28] | (b[29] << 8)) & 0x3FFF);
  } else {
    return Incomplete(h, "a WebP file without an image chunk");
  }
  return h;
}

ImageHeader Format(const char* name) {
  ImageHeader h;
  h.format = name;
  return h;
}

}  // namespace

ImageHeader InspectImage(std::span<const std::uint8_t> b) {
  const auto starts = [&](const char* magic, std::size_t at = 0) {
    const std::size_t n = std::strlen(magic);
    return b.size() >= at + n && std::memcmp(b.data() + at, magic, n) == 0;
  };
  if (b.size() >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF) return InspectJpeg(b);
  if (starts("\x89PNG\r\n\x1a\n")) return InspectPng(b);
  if (b.size() >= 4 && ((b[0] == 'I' && b[1] == 'I' && b[2] == 42 && b[3] == 0) ||
                        (b[0] == 'M' && b[1] == 'M' && b[2] == 0 && b[3] == 42))) {
    return Format("tiff");
  }
  if (starts("RIFF") && starts("WEBP", 8)) return InspectWebp(b);
  return {};
}

}  // namespace pintag::app
