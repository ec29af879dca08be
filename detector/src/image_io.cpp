// Photo bytes -> upright BGR pixels. OpenImageIO picks a reader from the file name, so the format
// is sniffed from the first bytes and a matching name is given with the in-memory proxy; nothing
// is decoded before the header's size has passed the pixel limit.

#include "pintag/detector/image_io.hpp"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <cstring>
#include <fstream>
#include <iterator>
#include <opencv2/core.hpp>
#include <vector>

namespace pintag {
namespace {

const char* SniffName(std::span<const std::uint8_t> b) {
  const auto starts = [&](const char* magic, std::size_t at = 0) {
    const std::size_t n = std::strlen(magic);
    return b.size() >= at + n && std::memcmp(b.data() + at, magic, n) == 0;
  };
  if (b.size() >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF) return "image.jpg";
  if (starts("\x89PNG\r\n\x1a\n")) return "image.png";
  if (starts("II*") || starts("MM")) {
    if (b.size() >= 4 && ((b[0] == 'I' && b[3] == 0) || (b[0] == 'M' && b[2] == 0 && b[3] == 42)))
      return "image.tif";
  }
  if (starts("RIFF") && starts("WEBP", 8)) return "image.webp";
  return nullptr;
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

}  // namespace

LoadResult LoadImageBytes(std::span<const std::uint8_t> bytes, std::int64_t max_pixels) {
  LoadResult result;
  if (bytes.empty()) {
    result.error = "empty input";
    return result;
  }
  const char* name = SniffName(bytes);
  if (!name) {
    result.error = "not a JPEG, PNG, TIFF or WebP image";
    return result;
  }
  OIIO::Filesystem::IOMemReader reader(bytes.data(), bytes.size());
  OIIO::Filesystem::IOProxy* proxy = &reader;
  OIIO::ImageSpec config;
  config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
  auto input = OIIO::ImageInput::open(name, &config);
  if (!input) {
    result.error = "cannot read image: " + OIIO::geterror();
    return result;
  }
  const OIIO::ImageSpec spec = input->spec();
  const std::int64_t pixels = static_cast<std::int64_t>(spec.width) * spec.height;
  if (spec.width < 1 || spec.height < 1 || spec.depth > 1 || spec.nchannels < 1) {
    result.error = "image has no pixels";
    return result;
  }
  if (pixels > max_pixels) {
    result.error = "image too large: " + std::to_string(spec.width) + "x" +
                   std::to_string(spec.height) + " exceeds " + std::to_string(max_pixels) +
                   " pixels";
    return result;
  }
  const int channels = spec.nchannels;
  std::vector<std::uint8_t> data(static_cast<std::size_t>(pixels) * channels);
  if (!input->read_image(0, 0, 0, channels, OIIO::TypeDesc::UINT8, data.data())) {
    result.error = "cannot decode image: " + input->geterror();
    return result;
  }
  const std::string format = input->format_name();
  input->close();

  cv::Mat bgr(spec.height, spec.width, CV_8UC3);
  for (int y = 0; y < spec.height; ++y) {
    const std::uint8_t* src = data.data() + static_cast<std::size_t>(y) * spec.width * channels;
    std::uint8_t* dst = bgr.ptr<std::uint8_t>(y);
    for (int x = 0; x < spec.width; ++x, src += channels, dst += 3) {
      if (channels >= 3) {
        dst[0] = src[2], dst[1] = src[1], dst[2] = src[0];
      } else {
        dst[0] = dst[1] = dst[2] = src[0];  // grey (and grey + alpha)
      }
    }
  }

  LoadedImage image;
  image.exif_orientation = spec.get_int_attribute("Orientation", 1);
  image.bgr = Reorient(bgr, image.exif_orientation);
  image.format = format;
  image.exif.focal_length_35mm = PositiveFloat(spec, "Exif:FocalLengthIn35mmFilm");
  image.exif.focal_length_mm = PositiveFloat(spec, "Exif:FocalLength");
  image.exif.focal_plane_x_resolution = PositiveFloat(spec, "Exif:FocalPlaneXResolution");
  const int unit = spec.get_int_attribute("Exif:FocalPlaneResolutionUnit", 0);
  if (unit > 0) image.exif.focal_plane_resolution_unit = unit;
  result.image = std::move(image);
  return result;
}

LoadResult LoadImageFile(const std::string& path, std::int64_t max_pixels) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {std::nullopt, "cannot open " + path};
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                        std::istreambuf_iterator<char>());
  LoadResult result = LoadImageBytes(bytes, max_pixels);
  if (!result.error.empty()) result.error = path + ": " + result.error;
  return result;
}

}  // namespace pintag
