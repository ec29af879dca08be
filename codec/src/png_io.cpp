#include "pintag/codec/png_io.hpp"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <string_view>

#include "pintag/codec/file_output.hpp"

namespace pintag {
namespace {

constexpr int kPngFilterNone = 0x08;  // libpng's PNG_FILTER_NONE, as OpenImageIO's png:filter

OIIO::ImageSpec PngSpec(const RgbImage& image, double dpi) {
  OIIO::ImageSpec spec(image.width, image.height, 3, OIIO::TypeDesc::UINT8);
  // OpenImageIO writes pHYs only from float resolutions; an int attribute is silently ignored.
  spec.attribute("XResolution", static_cast<float>(dpi));
  spec.attribute("YResolution", static_cast<float>(dpi));
  spec.attribute("ResolutionUnit", "inch");
  // Labels and tags are flat colour with sharp edges: libpng's default (try every row filter, zlib
  // level 6) spent about 60 % of a 300 dpi label's time for a file a quarter smaller than zlib
  // level 3 without filtering, which encodes about 7 times faster (measured on a 1181 x 1772
  // label: 140 -> 19 ms, 72 -> 96 KB).
  spec.attribute("png:compressionLevel", 3);
  spec.attribute("png:filter", kPngFilterNone);
  return spec;
}

}  // namespace

std::vector<std::uint8_t> EncodePng(const RgbImage& image, double dpi, std::string* error) {
  auto out = OIIO::ImageOutput::create("png");
  if (!out) {
    *error = "no PNG writer: " + OIIO::geterror();
    return {};
  }
  std::vector<unsigned char> bytes;
  OIIO::Filesystem::IOVecOutput vec_output(bytes);
  OIIO::Filesystem::IOProxy* proxy = &vec_output;
  OIIO::ImageSpec spec = PngSpec(image, dpi);
  spec.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
  if (!out->open("memory.png", spec) ||
      !out->write_image(OIIO::TypeDesc::UINT8, image.pixels.data()) || !out->close()) {
    *error = "cannot encode PNG: " + out->geterror();
    return {};
  }
  return {bytes.begin(), bytes.end()};
}

bool WritePng(const RgbImage& image, const std::string& path, double dpi, std::string* error) {
  // Encoded in memory and written whole: OpenImageIO's PNG writer does not check the close of
  // its file, so on a full disk (the last buffer never written) it reported success.
  const std::vector<std::uint8_t> bytes = EncodePng(image, dpi, error);
  if (bytes.empty()) return false;
  const std::string failure = WriteWholeFile(
      path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
  if (failure.empty()) return true;
  *error = "cannot write PNG " + path + ": " + failure;
  return false;
}

}  // namespace pintag
