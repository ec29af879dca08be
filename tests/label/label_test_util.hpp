#pragma once
// Helpers shared by the label tests: sample labels, reading PNGs back, running poppler (scratch
// directories and files: pintag/test/files.hpp).

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "pintag/codec/label.hpp"
#include "pintag/test/files.hpp"

namespace pintag::test {

inline LabelContent SampleLabel(std::uint32_t pincode = 110001, std::uint16_t key = 12345) {
  return {Pincode(pincode), TagKey(key),         "Connaught Place S.O",   "New Delhi",
          "Delhi",          std::string("N-07"), std::string("north-hub")};
}

struct DecodedPng {
  RgbImage image;
  OIIO::ImageSpec spec;
};

/// Reads PNG bytes through OpenImageIO from memory, as the server will.
inline std::optional<DecodedPng> ReadPng(const std::vector<std::uint8_t>& bytes) {
  OIIO::Filesystem::IOMemReader reader(const_cast<std::uint8_t*>(bytes.data()), bytes.size());
  OIIO::Filesystem::IOProxy* proxy = &reader;
  OIIO::ImageSpec config;
  config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
  auto in = OIIO::ImageInput::open("label.png", &config);
  if (!in) return std::nullopt;
  DecodedPng out;
  out.spec = in->spec();
  if (out.spec.nchannels < 3) return std::nullopt;
  std::vector<std::uint8_t> all(static_cast<std::size_t>(out.spec.width) * out.spec.height *
                                out.spec.nchannels);
  if (!in->read_image(0, 0, 0, out.spec.nchannels, OIIO::TypeDesc::UINT8, all.data())) {
    return std::nullopt;
  }
  out.image = RgbImage(out.spec.width, out.spec.height);
  for (std::size_t i = 0, n = static_cast<std::size_t>(out.spec.width) * out.spec.height; i < n;
       ++i) {
    for (int c = 0; c < 3; ++c) out.image.pixels[i * 3 + c] = all[i * out.spec.nchannels + c];
  }
  return out;
}

/// Runs a shell command and returns its standard output; nothing when it cannot run or fails.
inline std::optional<std::string> Run(const std::string& command) {
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(command.c_str(), "r"), pclose);
  if (!pipe) return std::nullopt;
  std::string out;
  char buffer[4096];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe.get())) > 0) out.append(buffer, n);
  if (pclose(pipe.release()) != 0) return std::nullopt;
  return out;
}

inline bool HavePoppler() {
  return Run("command -v pdfinfo >/dev/null && command -v pdftoppm >/dev/null && "
             "command -v pdffonts >/dev/null && echo yes")
      .has_value();
}

}  // namespace pintag::test
