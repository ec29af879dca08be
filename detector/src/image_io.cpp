// Photo bytes -> upright BGR pixels. JPEG, nearly every upload, is decoded by libjpeg-turbo
// straight into BGR (OpenImageIO's JPEG reader costs a copy to RGB and one back, about twice the
// time); OpenImageIO stays for the other formats and parses the EXIF block. Each format's header
// gives the stored size first, so the pixel limit is checked before anything is allocated.

#include "pintag/detector/image_io.hpp"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/tiffutils.h>
#include <turbojpeg.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstddef>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <limits>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace pintag {
namespace {

LoadResult Fail(ImageError kind, std::string error, int width = 0, int height = 0) {
  LoadResult result;
  result.kind = kind;
  result.error = std::move(error);
  result.claimed_width = width;
  result.claimed_height = height;
  return result;
}

std::string TooLargeMessage(int width, int height, std::int64_t max_pixels) {
  return "the image is " + std::to_string(width) + " x " + std::to_string(height) +
         " pixels; at most " + std::to_string(max_pixels) + " pixels are decoded";
}

bool OverLimit(int width, int height, std::int64_t max_pixels) {
  return std::int64_t{width} * height > max_pixels;
}

std::uint32_t Be16(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 8) | p[1];
}
std::uint32_t Be32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         p[3];
}
std::uint32_t Le32(const std::uint8_t* p) {
  return p[0] | (std::uint32_t{p[1]} << 8) | (std::uint32_t{p[2]} << 16) |
         (std::uint32_t{p[3]} << 24);
}

cv::Mat Reorient(const cv::Mat& in, int orientation) {
  cv::Mat out;
  switch (orientation) {
    case 2:
      cv::flip(in, out, 1);
      return out;
    case 3:
      cv::flip(in, out, -1);
      return out;
    case 4:
      cv::flip(in, out, 0);
      return out;
    case 5:
      cv::transpose(in, out);
      return out;
    case 6:
      cv::rotate(in, out, cv::ROTATE_90_CLOCKWISE);
      return out;
    case 7:
      cv::transpose(in, out);
      cv::flip(out, out, -1);
      return out;
    case 8:
      cv::rotate(in, out, cv::ROTATE_90_COUNTERCLOCKWISE);
      return out;
    default:
      return in;
  }
}

std::optional<double> PositiveFloat(const OIIO::ImageSpec& spec, const char* name) {
  const float v = spec.get_float_attribute(name, 0.0f);
  if (v > 0) return v;
  return std::nullopt;
}

/// Orientation and the camera fields the detector's intrinsics use, from OpenImageIO attributes.
void TakeExif(const OIIO::ImageSpec& spec, LoadedImage* image) {
  image->exif_orientation = spec.get_int_attribute("Orientation", 1);
  if (image->exif_orientation < 1 || image->exif_orientation > 8) image->exif_orientation = 1;
  image->exif.focal_length_35mm = PositiveFloat(spec, "Exif:FocalLengthIn35mmFilm");
  image->exif.focal_length_mm = PositiveFloat(spec, "Exif:FocalLength");
  image->exif.focal_plane_x_resolution = PositiveFloat(spec, "Exif:FocalPlaneXResolution");
  const int unit = spec.get_int_attribute("Exif:FocalPlaneResolutionUnit", 0);
  if (unit > 0) image->exif.focal_plane_resolution_unit = unit;
}

// ---- JPEG: libjpeg-turbo ----

/// Calls `visit(marker, payload, at)` for each marker segment before the first scan, `payload`
/// being the bytes after its length field and `at` the offset of its 0xFF; stops early when
/// `visit` returns false, and at the first segment that does not fit the file.
template <typename Visit>
void ForEachHeaderSegment(std::span<const std::uint8_t> b, Visit visit) {
  std::size_t pos = 2;
  while (pos + 4 <= b.size() && b[pos] == 0xFF) {
    const std::uint8_t marker = b[pos + 1];
    if (marker == 0xFF) {  // fill byte
      ++pos;
      continue;
    }
    if (marker == 0xDA || marker == 0xD9) return;  // scan data (or the end) follows
    const std::size_t length = Be16(&b[pos + 2]);
    if (length < 2 || pos + 2 + length > b.size()) return;
    if (!visit(marker, b.subspan(pos + 4, length - 2), pos)) return;
    pos += 2 + length;
  }
}

/// The EXIF block (APP1 "Exif\0\0") among the markers before the first scan; empty when none.
std::span<const std::uint8_t> JpegExifBlock(std::span<const std::uint8_t> b) {
  static constexpr char kExif[] = {'E', 'x', 'i', 'f', 0, 0};
  std::span<const std::uint8_t> found;
  ForEachHeaderSegment(
      b, [&](std::uint8_t marker, std::span<const std::uint8_t> payload, std::size_t /*at*/) {
        if (marker == 0xE1 && payload.size() >= sizeof kExif &&
            std::memcmp(payload.data(), kExif, sizeof kExif) == 0) {
          found = payload.subspan(sizeof kExif);
          return false;
        }
        return true;
      });
  return found;
}

/// Why libjpeg-turbo cannot decode this JPEG's frame at all, or empty: its first start-of-frame
/// marker says lossless or hierarchical coding, or a sample precision other than 8 bits (medical
/// and archival encoders, not cameras). libjpeg would call these corrupt; they are unsupported.
std::string UnsupportedJpegFrame(std::span<const std::uint8_t> b) {
  std::string why;
  ForEachHeaderSegment(
      b, [&](std::uint8_t marker, std::span<const std::uint8_t> payload, std::size_t /*at*/) {
        // SOF0 to SOF15, less DHT (C4), JPG (C8) and DAC (CC), which share the range.
        if (marker < 0xC0 || marker > 0xCF || marker == 0xC4 || marker == 0xC8 || marker == 0xCC) {
          return true;
        }
        const int process = marker - 0xC0;
        if (process % 4 == 3) {
          why = "the JPEG is lossless (SOF" + std::to_string(process) +
                "); only lossy 8-bit JPEGs, as cameras save them, are read";
        } else if (process == 5 || process == 6 || process == 13 || process == 14) {
          why = "the JPEG is hierarchical (SOF" + std::to_string(process) +
                "); only lossy 8-bit JPEGs, as cameras save them, are read";
        } else if (!payload.empty() && payload[0] != 8) {
          why = "the JPEG has " + std::to_string(payload[0]) +
                "-bit samples; only lossy 8-bit JPEGs, as cameras save them, are read";
        }
        return false;
      });
  return why;
}

/// A copy of the JPEG with every JFIF header's major version set to 1 (libjpeg-turbo warns on
/// any other, "JFIF 2.01", and a warning stops the decode), or nothing when none needs it. The
/// version only names the header's layout, which has not changed; the pixels do not depend on it.
std::optional<std::vector<std::uint8_t>> WithJfifVersionOne(std::span<const std::uint8_t> b) {
  static constexpr char kJfif[] = {'J', 'F', 'I', 'F', 0};
  std::vector<std::size_t> versions;  // offsets of the major version bytes to set
  ForEachHeaderSegment(
      b, [&](std::uint8_t marker, std::span<const std::uint8_t> payload, std::size_t at) {
        if (marker == 0xE0 && payload.size() >= sizeof kJfif + 2 &&
            std::memcmp(payload.data(), kJfif, sizeof kJfif) == 0 && payload[sizeof kJfif] != 1) {
          versions.push_back(at + 4 + sizeof kJfif);
        }
        return true;
      });
  if (versions.empty()) return std::nullopt;
  std::vector<std::uint8_t> copy(b.begin(), b.end());
  for (const std::size_t at : versions) {
    copy[at] = 1;
    copy[at + 1] = 2;  // minor version: 1.02, the last JFIF 1 revision
  }
  return copy;
}

/// Orientation and camera fields from a TIFF-structured EXIF block, when it is one.
void TakeExifBlock(std::span<const std::uint8_t> exif, LoadedImage* image) {
  if (exif.empty()) return;
  OIIO::ImageSpec spec;
  // A broken EXIF block loses the orientation and focal length, not the photo.
  if (OIIO::decode_exif(OIIO::cspan<std::uint8_t>(exif.data(), exif.size()), spec)) {
    TakeExif(spec, image);
  }
}

void TakeJpegExif(std::span<const std::uint8_t> bytes, LoadedImage* image) {
  TakeExifBlock(JpegExifBlock(bytes), image);
}

struct TurboDeleter {
  void operator()(void* handle) const { tjDestroy(handle); }
};

/// One decompressor per thread, reused: creating one costs more than reading a small header.
std::unique_ptr<void, TurboDeleter>& ThreadDecompressor() {
  thread_local std::unique_ptr<void, TurboDeleter> handle(tjInitDecompress());
  return handle;
}

tjhandle Decompressor() {
  return ThreadDecompressor().get();
}

/// After a failed call TurboJPEG 2.1 leaves the handle mid-file (the next file then fails with a
/// stale "Bogus DQT index"): start the thread's next file on a new one.
void DiscardDecompressor() {
  ThreadDecompressor().reset(tjInitDecompress());
}

// Truncated files only warn in libjpeg (the bottom is filled in grey): refuse them. Progressive
// files with an absurd number of scans are a known way to burn CPU: refuse those too.
constexpr int kTurboFlags = TJFLAG_STOPONWARNING | TJFLAG_LIMITSCANS;
/// TJFLAG_LIMITSCANS's limit, applied by us to the JPEGs OpenImageIO decodes (CMYK, YCCK).
constexpr int kMaxJpegScans = 500;

/// The start-of-scan markers in a JPEG, counted by walking its segments and skipping each scan's
/// entropy-coded data (where 0xFF is followed by 0x00 or a restart marker), as libjpeg reads
/// them; stops counting past `limit`.
int CountJpegScans(std::span<const std::uint8_t> b, int limit) {
  int scans = 0;
  std::size_t pos = 2;  // after SOI
  while (pos + 4 <= b.size() && scans <= limit) {
    // Bytes that are not a marker are skipped to the next one, as libjpeg skips them.
    if (b[pos] != 0xFF || b[pos + 1] == 0xFF || b[pos + 1] == 0x00) {
      ++pos;
      continue;
    }
    const std::uint8_t marker = b[pos + 1];
    if (marker == 0xD9) return scans;                            // EOI
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) {  // markers without a length
      pos += 2;
      continue;
    }
    const std::size_t length = (std::size_t{b[pos + 2]} << 8) | b[pos + 3];
    pos += 2 + length;
    if (marker != 0xDA) continue;
    ++scans;
    while (pos + 1 < b.size() &&
           !(b[pos] == 0xFF && b[pos + 1] != 0x00 && (b[pos + 1] < 0xD0 || b[pos + 1] > 0xD7))) {
      ++pos;
    }
  }
  return scans;
}

/// Runs `decode(handle)`, one TurboJPEG decompression with kTurboFlags into the caller's buffers;
/// on failure (any warning: truncation is one) `error` says why and the handle is replaced. Stray
/// bytes before the end marker are refused too when libjpeg warns of them: a cut file followed by
/// bytes and an end marker gives the same warning when the decoder took the bytes as its data.
template <typename Decode>
bool DecodeWholeJpeg(Decode decode, std::string* error) {
  if (decode(Decompressor()) == 0) return true;
  *error = std::string("cannot decode the JPEG: ") + tjGetErrorStr2(Decompressor());
  DiscardDecompressor();
  return false;
}

struct JpegHeader {
  int width = 0;
  int height = 0;
  int subsampling = 0;
  int colourspace = 0;
};

std::optional<JpegHeader> ReadJpegHeader(tjhandle tj, std::span<const std::uint8_t> bytes,
                                         std::string* error) {
  JpegHeader h;
  if (tjDecompressHeader3(tj, bytes.data(), bytes.size(), &h.width, &h.height, &h.subsampling,
                          &h.colourspace) != 0) {
    *error = std::string("cannot read the JPEG header: ") + tjGetErrorStr2(tj);
    DiscardDecompressor();
    return std::nullopt;
  }
  return h;
}

/// The largest libjpeg-turbo scaling factor 1/denominator, or 1/1 for anything not offered.
tjscalingfactor ScalingFor(int denominator) {
  int count = 0;
  const tjscalingfactor* factors = tjGetScalingFactors(&count);
  for (int i = 0; i < count; ++i) {
    if (factors[i].num == 1 && factors[i].denom == denominator) return factors[i];
  }
  return {1, 1};
}

/// `size_told`: before_decode was already called with the size our own header parser read (PNG,
/// WebP); otherwise it is called here once OpenImageIO has read the header.
LoadResult LoadWithOpenImageIo(std::span<const std::uint8_t> bytes, ImageFormat format,
                               const LoadOptions& options, bool size_told = false);

/// Orientations 5 to 8 swap the image's axes.
bool Transposes(int exif_orientation) {
  return exif_orientation >= 5 && exif_orientation <= 8;
}

/// What TurboJPEG's full-size decode did to a JPEG's chroma (libjpeg's default upsampling: the
/// triangle filter, "fancy"), in the axes of the image after `exif_orientation`. The reader takes
/// chroma blocks to start at even coordinates: an orientation that mirrors a stored axis of odd
/// length moves them to odd ones, and such an image is reported as kNone (not modelled).
ChromaUpsampling JpegChromaUpsampling(int subsampling, int exif_orientation, int stored_width,
                                      int stored_height) {
  const int o = exif_orientation;
  const bool mirrors_x = o == 2 || o == 3 || o == 7 || o == 8;  // the stored columns' order
  const bool mirrors_y = o == 3 || o == 4 || o == 6 || o == 7;  // the stored rows' order
  if ((mirrors_x && stored_width % 2 != 0) || (mirrors_y && stored_height % 2 != 0)) {
    return ChromaUpsampling::kNone;
  }
  ChromaUpsampling stored = ChromaUpsampling::kNone;
  if (subsampling == TJSAMP_420) stored = ChromaUpsampling::kBoth;
  if (subsampling == TJSAMP_422) stored = ChromaUpsampling::kAcross;
  if (subsampling == TJSAMP_440) stored = ChromaUpsampling::kDown;
  if (!Transposes(exif_orientation)) return stored;
  if (stored == ChromaUpsampling::kAcross) return ChromaUpsampling::kDown;
  if (stored == ChromaUpsampling::kDown) return ChromaUpsampling::kAcross;
  return stored;
}

LoadResult LoadJpeg(std::span<const std::uint8_t> bytes, const LoadOptions& options) {
  tjhandle tj = Decompressor();
  if (tj == nullptr) return Fail(ImageError::kCorrupt, "cannot start the JPEG decoder");
  std::string why = UnsupportedJpegFrame(bytes);
  if (!why.empty()) return Fail(ImageError::kUnsupported, why);
  const std::optional<std::vector<std::uint8_t>> jfif_one = WithJfifVersionOne(bytes);
  if (jfif_one) bytes = *jfif_one;
  const std::optional<JpegHeader> header = ReadJpegHeader(tj, bytes, &why);
  if (!header) return Fail(ImageError::kCorrupt, why);
  if (header->width < 1 || header->height < 1) {
    return Fail(ImageError::kCorrupt, "the JPEG has no pixels");
  }
  if (OverLimit(header->width, header->height, options.max_pixels)) {
    return Fail(ImageError::kTooLarge,
                TooLargeMessage(header->width, header->height, options.max_pixels), header->width,
                header->height);
  }
  // CMYK and YCCK (print workflows, not phones) cannot be decoded to BGR by TurboJPEG.
  if (header->colourspace == TJCS_CMYK || header->colourspace == TJCS_YCCK) {
    // libjpeg under OpenImageIO decodes every scan it is given: 20,000 scans of a 12 MP CMYK
    // photo took a minute of CPU.
    if (CountJpegScans(bytes, kMaxJpegScans) > kMaxJpegScans) {
      return Fail(ImageError::kCorrupt,
                  "the JPEG has more than " + std::to_string(kMaxJpegScans) + " scans",
                  header->width, header->height);
    }
    return LoadWithOpenImageIo(bytes, ImageFormat::kJpeg, options);
  }
  if (options.before_decode) options.before_decode(header->width, header->height);
  const tjscalingfactor scale = ScalingFor(options.scale_denominator);
  cv::Mat bgr(TJSCALED(header->height, scale), TJSCALED(header->width, scale), CV_8UC3);
  const auto decode = [&](tjhandle handle) {
    return tjDecompress2(handle, bytes.data(), bytes.size(), bgr.data, bgr.cols,
                         static_cast<int>(bgr.step), bgr.rows, TJPF_BGR, kTurboFlags);
  };
  if (!DecodeWholeJpeg(decode, &why)) {
    return Fail(ImageError::kCorrupt, why, header->width, header->height);
  }
  LoadedImage image;
  image.format = "jpeg";
  TakeJpegExif(bytes, &image);
  image.bgr = Reorient(bgr, image.exif_orientation);
  // A scaled decode handles chroma in its reduced transforms: not modelled, left as it is.
  const bool full_size = scale.num == scale.denom;
  image.chroma_upsampling = full_size
                                ? JpegChromaUpsampling(header->subsampling, image.exif_orientation,
                                                       header->width, header->height)
                                : ChromaUpsampling::kNone;
  LoadResult result;
  result.claimed_width = header->width;
  result.claimed_height = header->height;
  result.image = std::move(image);
  return result;
}

// ---- PNG: structure checked here, pixels through OpenImageIO ----

/// The size a PNG's or WebP's header claims, read before any decoder runs. Empty `problem` when
/// the header (for PNG: every chunk to IEND) is whole.
struct HeaderSize {
  int width = 0;
  int height = 0;
  std::string problem;
};

#ifdef PINTAG_FUZZ_SKIPS_PNG_CHECKSUMS
constexpr bool kCheckPngChecksums = false;
#else
constexpr bool kCheckPngChecksums = true;
#endif

/// Whether a PNG chunk's four type bytes are letters, as the format (and libpng) requires.
bool IsPngChunkType(const std::uint8_t* type) {
  return std::all_of(type, type + 4, [](std::uint8_t c) {
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z');
  });
}

/// The name of a PNG chunk's type for a message: its four letters, or their bytes in hex when
/// damage has made them something else.
std::string PngChunkName(const std::uint8_t* type) {
  if (IsPngChunkType(type)) return {reinterpret_cast<const char*>(type), 4};
  static constexpr char kHex[] = "0123456789abcdef";
  std::string hex = "0x";
  for (int i = 0; i < 4; ++i) {
    hex += kHex[type[i] >> 4];
    hex += kHex[type[i] & 0xF];
  }
  return hex;
}

/// Walks the chunks from IHDR to IEND: libpng decodes a truncated file's missing rows as zeros,
/// so a cut upload is caught here. A critical chunk (IHDR, PLTE, IDAT, IEND: an upper-case
/// first letter) whose checksum fails is damage too. libpng refuses it as well, but prints
/// "libpng error: ..." to stderr on its way, a plain line among the server's JSON log lines.
/// Ancillary chunks are left to libpng, which drops a damaged one and reads the image.
HeaderSize InspectPng(std::span<const std::uint8_t> b) {
  HeaderSize h;
  std::size_t pos = 8;
  bool first = true;
  while (true) {
    if (pos + 12 > b.size()) {
      h.problem = "the PNG is truncated (no IEND chunk)";
      return h;
    }
    const std::uint32_t length = Be32(&b[pos]);
    if (length > 0x7FFFFFFFu || pos + 12 + length > b.size()) {
      h.problem = "the PNG is truncated inside a chunk";
      return h;
    }
    // A type of anything but four letters is libpng's "invalid chunk type", printed as above.
    if (!IsPngChunkType(&b[pos + 4])) {
      h.problem = "the PNG is damaged: a chunk's type is " + PngChunkName(&b[pos + 4]) +
                  ", not four letters";
      return h;
    }
    const bool critical = (b[pos + 4] & 0x20U) == 0;
    if (kCheckPngChecksums && critical &&
        crc32(0, &b[pos + 4], length + 4) != Be32(&b[pos + 8 + length])) {
      h.problem = "the PNG is damaged: its " + PngChunkName(&b[pos + 4]) +
                  " chunk fails its checksum (CRC)";
      return h;
    }
    const bool ihdr = std::memcmp(&b[pos + 4], "IHDR", 4) == 0;
    if (first) {
      if (!ihdr || length < 8) {
        h.problem = "the PNG does not start with IHDR";
        return h;
      }
      const std::uint32_t width = Be32(&b[pos + 8]);
      const std::uint32_t height = Be32(&b[pos + 12]);
      // The PNG format allows 1 to 2^31 - 1 pixels a side: a size outside is damage, not a
      // large photo (it was clamped and reported as 2147483647 pixels, "too large").
      if (width == 0 || height == 0 || width > 0x7FFFFFFFu || height > 0x7FFFFFFFu) {
        h.problem = "the PNG's header gives a size of " + std::to_string(width) + " x " +
                    std::to_string(height) + " pixels, outside what a PNG can hold (1 to " +
                    "2147483647 a side)";
        return h;
      }
      h.width = static_cast<int>(width);
      h.height = static_cast<int>(height);
      first = false;
    }
    if (std::memcmp(&b[pos + 4], "IEND", 4) == 0) return h;
    pos += 12 + length;
  }
}

/// Whether a WebP holds a lossy (VP8, 4:2:0) image: its first image chunk is "VP8 ", not "VP8L".
/// In an animation that is the first frame's (the one decoded): the image chunk inside the first
/// ANMF chunk, after its 16 bytes of frame header.
bool WebpIsLossy(std::span<const std::uint8_t> b) {
  constexpr std::size_t kFrameHeaderBytes = 16;
  std::size_t pos = 12;
  std::size_t end = b.size();
  while (pos + 8 <= end) {
    if (std::memcmp(&b[pos], "VP8 ", 4) == 0) return true;
    if (std::memcmp(&b[pos], "VP8L", 4) == 0) return false;
    const std::size_t size = Le32(&b[pos + 4]);
    if (size > end - pos - 8) return false;  // a chunk past the end: nothing more to find
    if (std::memcmp(&b[pos], "ANMF", 4) == 0 && size >= kFrameHeaderBytes) {
      end = pos + 8 + size;  // the first frame's own chunks, and no further
      pos += 8 + kFrameHeaderBytes;
      continue;
    }
    pos += 8 + size + (size & 1);
  }
  return false;
}

/// A WebP's EXIF chunk (TIFF-structured, as in a JPEG's APP1 after "Exif\0\0", which some
/// writers repeat here); empty when none. OpenImageIO 2.4 does not read it.
std::span<const std::uint8_t> WebpExifChunk(std::span<const std::uint8_t> b) {
  static constexpr char kExif[] = {'E', 'x', 'i', 'f', 0, 0};
  std::size_t pos = 12;
  while (pos + 8 <= b.size()) {
    const std::size_t size = Le32(&b[pos + 4]);
    if (size > b.size() - pos - 8) return {};
    if (std::memcmp(&b[pos], "EXIF", 4) == 0) {
      std::span<const std::uint8_t> exif = b.subspan(pos + 8, size);
      if (exif.size() >= sizeof kExif && std::memcmp(exif.data(), kExif, sizeof kExif) == 0) {
        exif = exif.subspan(sizeof kExif);
      }
      return exif;
    }
    pos += 8 + size + (size & 1);
  }
  return {};
}

/// A WebP's canvas size from its first chunk (VP8X extended, VP8L lossless, or "VP8 " lossy).
/// OpenImageIO decodes a WebP as soon as it opens it, so the pixel limit must be checked here,
/// before it does: a tiny file claiming 16383 × 16383 would otherwise be decoded.
HeaderSize InspectWebp(std::span<const std::uint8_t> b) {
  HeaderSize h;
  const auto le24 = [&](std::size_t at) {
    return b[at] | (std::uint32_t{b[at + 1]} << 8) | (std::uint32_t{b[at + 2]} << 16);
  };
  const auto chunk = [&](const char* fourcc) {
    return b.size() >= 16 && std::memcmp(b.data() + 12, fourcc, 4) == 0;
  };
  if (chunk("VP8X")) {
    if (b.size() < 30) {
      h.problem = "the WebP header is truncated";
      return h;
    }
    h.width = static_cast<int>(le24(24) + 1);
    h.height = static_cast<int>(le24(27) + 1);
  } else if (chunk("VP8L")) {
    if (b.size() < 25 || b[20] != 0x2f) {
      h.problem = "the WebP header is truncated";
      return h;
    }
    const std::uint32_t bits = le24(21) | (std::uint32_t{b[24]} << 24);
    h.width = static_cast<int>((bits & 0x3FFFU) + 1);
    h.height = static_cast<int>(((bits >> 14) & 0x3FFFU) + 1);
  } else if (chunk("VP8 ")) {
    if (b.size() < 30 || b[23] != 0x9d || b[24] != 0x01 || b[25] != 0x2a) {
      h.problem = "the WebP header is truncated";
      return h;
    }
    h.width = static_cast<int>((b[26] | (b[27] << 8)) & 0x3FFF);
    h.height = static_cast<int>((b[28] | (b[29] << 8)) & 0x3FFF);
  } else {
    h.problem = "a WebP file without an image chunk";
  }
  return h;
}

// ---- PNG, TIFF, WebP (and CMYK JPEG): OpenImageIO ----

const char* ProxyName(ImageFormat format) {
  // OpenImageIO picks its reader from the file name given with the in-memory proxy.
  switch (format) {
    case ImageFormat::kJpeg:
      return "image.jpg";
    case ImageFormat::kPng:
      return "image.png";
    case ImageFormat::kTiff:
      return "image.tif";
    case ImageFormat::kWebp:
      return "image.webp";
    case ImageFormat::kUnknown:
      break;
  }
  return "image";
}

/// The first of a decoder's errors, with how many followed: a TIFF whose strips are missing
/// reports one per row, thousands of lines for a photo.
std::string FirstLine(const std::string& errors) {
  const std::size_t end = errors.find('\n');
  if (end == std::string::npos) return errors;
  std::size_t more = 0;
  for (std::size_t i = end; i < errors.size(); ++i)
    more += errors[i] == '\n' && i + 1 < errors.size();
  return errors.substr(0, end) +
         (more > 0 ? " (and " + std::to_string(more) + " more errors)" : std::string());
}

/// Rows of native pixels converted at a time when an image is not 8-bit.
constexpr std::size_t kNativeChunkBytes = std::size_t{4} << 20;

/// Reads every channel of subimage 0 as 8-bit values into `out` (width × height × channels).
/// OpenImageIO 2.4 converts a scanline image through a scratch buffer sized for 64 MB of rows,
/// whatever the image's height, whenever a type is asked for, even the file's own 8 bits. So an
/// 8-bit PNG or WebP is read in its native type (straight into `out`), and a deeper one (16-bit
/// PNG) as native rows a few MB at a time, converted by the same `convert_pixel_values`
/// OpenImageIO would use. TIFF keeps OpenImageIO's buffer: its native TIFF read can write past
/// the rows it was asked for (a fuzzed TIFF with 9994 bits per sample overran, then freed, memory
/// beyond ours; kept in fuzz/regressions/image_detect/).
bool ReadAs8Bit(OIIO::ImageInput& input, const OIIO::ImageSpec& spec, ImageFormat format,
                std::uint8_t* out) {
  const int channels = spec.nchannels;
  if (format == ImageFormat::kTiff || !spec.channelformats.empty() || spec.tile_width > 0) {
    return input.read_image(0, 0, 0, channels, OIIO::TypeDesc::UINT8, out);
  }
  if (spec.format == OIIO::TypeDesc::UINT8) {
    return input.read_image(0, 0, 0, channels, OIIO::TypeDesc::UNKNOWN, out);
  }
  const std::size_t native_row = spec.scanline_bytes(/*native=*/true);
  const std::size_t row_values = static_cast<std::size_t>(spec.width) * channels;
  constexpr auto kIntMax = static_cast<std::size_t>(std::numeric_limits<int>::max());
  // convert_pixel_values counts values in an int.
  if (native_row == 0 || row_values > kIntMax) return false;
  const int rows = static_cast<int>(
      std::clamp<std::size_t>(std::min(kNativeChunkBytes / native_row, kIntMax / row_values), 1,
                              static_cast<std::size_t>(spec.height)));
  std::vector<std::byte> native(static_cast<std::size_t>(rows) * native_row);
  for (int y = 0; y < spec.height; y += rows) {
    const int end = std::min(spec.height, y + rows);
    if (!input.read_scanlines(0, 0, spec.y + y, spec.y + end, 0, 0, channels,
                              OIIO::TypeDesc::UNKNOWN, native.data())) {
      return false;
    }
    if (!OIIO::convert_pixel_values(
            spec.format, native.data(), OIIO::TypeDesc::UINT8,
            out + static_cast<std::size_t>(y) * row_values,
            static_cast<int>(static_cast<std::size_t>(end - y) * row_values))) {
      return false;
    }
  }
  return true;
}

/// An 8-bit colour value with its alpha, composited over white; `straight`: the value is not
/// multiplied by alpha, else it is.
std::uint8_t OverWhite(std::uint8_t value, std::uint8_t alpha, bool straight) {
  const int transparency = 255 - alpha;
  if (straight) return static_cast<std::uint8_t>((value * alpha + 255 * transparency + 127) / 255);
  return static_cast<std::uint8_t>(std::min(255, value + transparency));
}

LoadResult LoadWithOpenImageIo(std::span<const std::uint8_t> bytes, ImageFormat format,
                               const LoadOptions& options, bool size_told) {
  OIIO::Filesystem::IOMemReader reader(bytes.data(), bytes.size());
  OIIO::Filesystem::IOProxy* proxy = &reader;
  OIIO::ImageSpec config;
  config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
  // Colour as stored, not multiplied by alpha: OverWhite does the compositing.
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto input = OIIO::ImageInput::open(ProxyName(format), &config);
  if (!input) return Fail(ImageError::kCorrupt, "cannot read image: " + OIIO::geterror());
  const OIIO::ImageSpec spec = input->spec();
  if (spec.width < 1 || spec.height < 1 || spec.depth > 1 || spec.nchannels < 1) {
    return Fail(ImageError::kCorrupt, "image has no pixels");
  }
  // Rows and columns are numbered from the image's origin (a PNG's oFFs chunk can put it near
  // INT_MAX): its last row and column must still be an int.
  constexpr int kIntMax = std::numeric_limits<int>::max();
  if (spec.x > kIntMax - spec.width || spec.y > kIntMax - spec.height) {
    return Fail(ImageError::kCorrupt, "the image's origin puts its pixels beyond the int range");
  }
  if (OverLimit(spec.width, spec.height, options.max_pixels)) {
    return Fail(ImageError::kTooLarge, TooLargeMessage(spec.width, spec.height, options.max_pixels),
                spec.width, spec.height);
  }
  // A tiled TIFF is decoded a tile at a time into a buffer of the tile's size, which the pixel
  // limit does not see: a 1 KB file of a 64 x 64 image in 16384 x 16384 tiles took 1.5 GB. A
  // tile may exceed the image only as far as tiles are rounded (to 16, or up to 1024 a side).
  if (spec.tile_width > 0 || spec.tile_height > 0) {
    const auto fits = [](int tile, int side) {
      return tile >= 0 && tile <= std::max(1024, (side + 15) / 16 * 16);
    };
    if (!fits(spec.tile_width, spec.width) || !fits(spec.tile_height, spec.height) ||
        spec.tile_depth > 1) {
      return Fail(ImageError::kTooLarge,
                  "the image is " + std::to_string(spec.width) + " x " +
                      std::to_string(spec.height) + " pixels in tiles of " +
                      std::to_string(spec.tile_width) + " x " + std::to_string(spec.tile_height) +
                      "; a tile may be at most 1024 pixels a side or the image's side",
                  spec.width, spec.height);
    }
  }
  // The pixel limit does not count channels, and decoding costs memory and time per channel: a
  // TIFF header of a few hundred bytes can declare a thousand.
  if (spec.nchannels > kMaxChannels) {
    return Fail(ImageError::kUnsupported,
                "the image has " + std::to_string(spec.nchannels) +
                    " channels; a photo has at most " + std::to_string(kMaxChannels) +
                    " (grey, grey and alpha, RGB or RGBA)",
                spec.width, spec.height);
  }
  if (!size_told && options.before_decode) options.before_decode(spec.width, spec.height);
  const int channels = spec.nchannels;
  std::vector<std::uint8_t> data(static_cast<std::size_t>(spec.width) * spec.height * channels);
  // OpenImageIO can read a TIFF whose strips lie past the end of the file and report the
  // failure only as a pending error: such rows were never decoded.
  if (!ReadAs8Bit(*input, spec, format, data.data()) || input->has_error()) {
    std::string why = FirstLine(input->geterror());
    if (why.empty()) why = "its rows cannot be addressed or converted to 8 bits";
    return Fail(ImageError::kCorrupt, "cannot decode image: " + why, spec.width, spec.height);
  }
  const std::string format_name = input->format_name();
  input->close();

  // Grey and alpha, or RGBA: composited over white, as the image shows on a page or prints. A
  // label or tag exported with a transparent background would otherwise read its transparent
  // pixels' colour, often black, and the tag's white quiet zone would be gone.
  const bool has_alpha = (channels == 2 || channels == 4) && spec.alpha_channel == channels - 1;
  // OpenImageIO marks colour it left unmultiplied, as asked (PNG, a TIFF that stores it so);
  // its WebP reader (2.4) multiplies whatever it is asked.
  const bool straight_alpha = spec.get_int_attribute("oiio:UnassociatedAlpha", 0) != 0;
  cv::Mat bgr(spec.height, spec.width, CV_8UC3);
  for (int y = 0; y < spec.height; ++y) {
    const std::uint8_t* src = data.data() + static_cast<std::size_t>(y) * spec.width * channels;
    auto* dst = bgr.ptr<std::uint8_t>(y);
    for (int x = 0; x < spec.width; ++x, src += channels, dst += 3) {
      if (channels >= 3) {
        dst[0] = src[2], dst[1] = src[1], dst[2] = src[0];
      } else {
        dst[0] = dst[1] = dst[2] = src[0];
      }
      if (has_alpha) {
        const std::uint8_t alpha = src[channels - 1];
        for (int c = 0; c < 3; ++c) dst[c] = OverWhite(dst[c], alpha, straight_alpha);
      }
    }
  }
  LoadedImage image;
  image.format = format_name;
  TakeExif(spec, &image);
  if (format == ImageFormat::kWebp) TakeExifBlock(WebpExifChunk(bytes), &image);
  image.bgr = Reorient(bgr, image.exif_orientation);
  // libwebp's default decode interpolates a lossy image's 4:2:0 chroma as libjpeg does. The
  // other formats (and CMYK JPEG, converted by OpenImageIO) are taken as full resolution.
  // Its blocks follow the stored axes, turned by the EXIF orientation as a JPEG's are.
  if (format == ImageFormat::kWebp && WebpIsLossy(bytes)) {
    image.chroma_upsampling =
        JpegChromaUpsampling(TJSAMP_420, image.exif_orientation, spec.width, spec.height);
  }
  LoadResult result;
  result.claimed_width = spec.width;
  result.claimed_height = spec.height;
  result.image = std::move(image);
  return result;
}

}  // namespace

const char* ToString(ImageError error) {
  switch (error) {
    case ImageError::kNone:
      return "none";
    case ImageError::kUnsupported:
      return "unsupported";
    case ImageError::kTooLarge:
      return "too_large";
    case ImageError::kCorrupt:
      return "corrupt";
    case ImageError::kUnreadable:
      return "unreadable";
  }
  return "unknown";
}

ImageFormat SniffImageFormat(std::span<const std::uint8_t> b) {
  const auto starts = [&](std::initializer_list<std::uint8_t> magic, std::size_t at = 0) {
    return b.size() >= at + magic.size() && std::equal(magic.begin(), magic.end(), b.begin() + at);
  };
  if (starts({0xFF, 0xD8, 0xFF})) return ImageFormat::kJpeg;
  if (starts({0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'})) return ImageFormat::kPng;
  if (starts({'I', 'I', 42, 0}) || starts({'M', 'M', 0, 42})) return ImageFormat::kTiff;
  if (starts({'I', 'I', 43, 0}) || starts({'M', 'M', 0, 43})) return ImageFormat::kTiff;  // BigTIFF
  if (starts({'R', 'I', 'F', 'F'}) && starts({'W', 'E', 'B', 'P'}, 8)) return ImageFormat::kWebp;
  return ImageFormat::kUnknown;
}

LoadResult LoadImageBytes(std::span<const std::uint8_t> bytes, const LoadOptions& options) {
  if (bytes.empty()) return Fail(ImageError::kUnsupported, "no image: the input is empty");
  const ImageFormat format = SniffImageFormat(bytes);
  switch (format) {
    case ImageFormat::kJpeg:
      return LoadJpeg(bytes, options);
    case ImageFormat::kPng:
    case ImageFormat::kWebp: {
      const HeaderSize header =
          format == ImageFormat::kPng ? InspectPng(bytes) : InspectWebp(bytes);
      if (header.width > 0 && header.height > 0 &&
          OverLimit(header.width, header.height, options.max_pixels)) {
        return Fail(ImageError::kTooLarge,
                    TooLargeMessage(header.width, header.height, options.max_pixels), header.width,
                    header.height);
      }
      if (!header.problem.empty()) {
        return Fail(ImageError::kCorrupt, header.problem, header.width, header.height);
      }
      // OpenImageIO decodes a whole WebP while it opens it: the size is told from our header.
      const bool size_known = header.width > 0 && header.height > 0;
      if (size_known && options.before_decode) options.before_decode(header.width, header.height);
      return LoadWithOpenImageIo(bytes, format, options, size_known);
    }
    case ImageFormat::kTiff:
      return LoadWithOpenImageIo(bytes, ImageFormat::kTiff, options);
    case ImageFormat::kUnknown:
      break;
  }
  return Fail(ImageError::kUnsupported, "not a JPEG, PNG, TIFF or WebP image");
}

LoadResult LoadImageBytes(std::span<const std::uint8_t> bytes, std::int64_t max_pixels) {
  LoadOptions options;
  options.max_pixels = max_pixels;
  return LoadImageBytes(bytes, options);
}

LoadResult LoadImageFile(const std::string& path, std::int64_t max_pixels) {
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) {
    return Fail(ImageError::kUnreadable, path + " is a directory, not a photo");
  }
  errno = 0;
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    // libstdc++ opens with open(2): errno says why (no such file, permission denied).
    const int why = errno;
    return Fail(ImageError::kUnreadable,
                "cannot open " + path + (why != 0 ? std::string(": ") + std::strerror(why) : ""));
  }
  constexpr std::size_t kMaxFileBytes = std::size_t{1} << 30;
  const bool regular = std::filesystem::is_regular_file(path, error);
  const std::uintmax_t size = regular ? std::filesystem::file_size(path, error) : 0;
  if (regular && !error && size > kMaxFileBytes) {
    return Fail(ImageError::kTooLarge, path + " is larger than 1 GiB, more than any photo");
  }
  return LoadImageStream(in, path, max_pixels, regular && !error ? size : 0);
}

LoadResult LoadImageStream(std::istream& in, const std::string& name, std::int64_t max_pixels,
                           std::size_t expected_bytes) {
  // Read up to one byte past the limit: a device or a pipe (/dev/zero) has no end to wait for.
  // A 40 MP photo as an uncompressed float RGBA TIFF is 640 MB.
  constexpr std::size_t kMaxBytes = std::size_t{1} << 30;
  std::vector<std::uint8_t> bytes;
  std::array<char, 1 << 16> chunk{};
  // Reserved once, never grown by doubling: a copy at each doubling took a photo's header
  // followed by endless bytes (a device) to 2.2 GB before the limit refused it. An unknown size
  // reserves the limit, of which only the pages read into are ever used.
  bytes.reserve(expected_bytes > 0 ? std::min(expected_bytes, kMaxBytes + 1)
                                   : kMaxBytes + chunk.size());
  while (bytes.size() <= kMaxBytes && in.read(chunk.data(), chunk.size()).gcount() > 0) {
    bytes.insert(bytes.end(), chunk.data(), chunk.data() + in.gcount());
    // A stream that does not start as a photo is refused from its first bytes, not after 1 GiB.
    if (bytes.size() >= kSniffImageBytes && SniffImageFormat(bytes) == ImageFormat::kUnknown) break;
  }
  if (bytes.size() > kMaxBytes) {
    return Fail(ImageError::kTooLarge, name + " holds more than 1 GiB, more than any photo");
  }
  LoadResult result = LoadImageBytes(bytes, max_pixels);
  if (!result.error.empty()) result.error = name + ": " + result.error;
  return result;
}

JpegPlanesResult LoadJpegPlanes(std::span<const std::uint8_t> bytes, std::int64_t max_pixels) {
  JpegPlanesResult result;
  const auto fail = [&](ImageError kind, std::string error) {
    result.kind = kind;
    result.error = std::move(error);
    return result;
  };
  if (SniffImageFormat(bytes) != ImageFormat::kJpeg) {
    return fail(ImageError::kUnsupported, "not a JPEG");
  }
  tjhandle tj = Decompressor();
  if (tj == nullptr) return fail(ImageError::kCorrupt, "cannot start the JPEG decoder");
  std::string why = UnsupportedJpegFrame(bytes);
  if (!why.empty()) return fail(ImageError::kUnsupported, why);
  const std::optional<std::vector<std::uint8_t>> jfif_one = WithJfifVersionOne(bytes);
  if (jfif_one) bytes = *jfif_one;
  const std::optional<JpegHeader> header = ReadJpegHeader(tj, bytes, &why);
  if (!header) return fail(ImageError::kCorrupt, why);
  if (OverLimit(header->width, header->height, max_pixels)) {
    return fail(ImageError::kTooLarge, TooLargeMessage(header->width, header->height, max_pixels));
  }
  if (header->colourspace == TJCS_CMYK || header->colourspace == TJCS_YCCK) {
    return fail(ImageError::kUnsupported, "a CMYK JPEG has no YCbCr planes");
  }
  JpegPlanes planes;
  const bool grey = header->subsampling == TJSAMP_GRAY;
  std::array<cv::Mat*, 3> mats = {&planes.y, &planes.cb, &planes.cr};
  std::array<unsigned char*, 3> pointers{};
  std::array<int, 3> strides{};
  for (int c = 0; c < (grey ? 1 : 3); ++c) {
    const int w = tjPlaneWidth(c, header->width, header->subsampling);
    const int h = tjPlaneHeight(c, header->height, header->subsampling);
    mats[c]->create(h, w, CV_8UC1);
    pointers[c] = mats[c]->data;
    strides[c] = static_cast<int>(mats[c]->step);
  }
  const auto decode = [&](tjhandle handle) {
    return tjDecompressToYUVPlanes(handle, bytes.data(), bytes.size(), pointers.data(),
                                   header->width, strides.data(), header->height, kTurboFlags);
  };
  if (!DecodeWholeJpeg(decode, &why)) return fail(ImageError::kCorrupt, why);
  LoadedImage exif;
  TakeJpegExif(bytes, &exif);
  planes.orientation = exif.exif_orientation;
  result.planes = std::move(planes);
  return result;
}

}  // namespace pintag
