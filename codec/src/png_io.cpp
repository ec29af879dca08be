#include "pintag/codec/png_io.hpp"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

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

bool Write(const RgbImage& image, const std::string& name, double dpi,
           OIIO::Filesystem::IOProxy* proxy, std::string* error) {
  auto out = OIIO::ImageOutput::create("png");
  if (!out) {
    *error = "no PNG writer: " + OIIO::geterror();
    return false;
  }
  OIIO::ImageSpec spec = PngSpec(image, dpi);
  if (proxy != nullptr) spec.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
  if (!out->open(name, spec) || !out->write_image(OIIO::TypeDesc::UINT8, image.pixels.data()) ||
      !out->close()) {
    *error = "cannot write PNG " + name + ": " + out->geterror();
    return false;
  }
  return true;
}

}  // namespace

std::vector<std::uint8_t> EncodePng(const RgbImage& image, double dpi, std::string* error) {
  std::vector<unsigned char> bytes;
  OIIO::Filesystem::IOVecOutput proxy(bytes);
  if (!Write(image, "memory.png", dpi, &proxy, error)) return {};
  return {bytes.begin(), bytes.end()};
}

bool WritePng(const RgbImage& image, const std::string& path, double dpi, std::string* error) {
  return Write(image, path, dpi, nullptr, error);
}

}  // namespace pintag
