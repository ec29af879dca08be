#pragma once
// Helpers shared by the label tests: sample labels, reading PNGs back, running poppler.

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "pintag/codec/label.hpp"

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

/// A scratch directory removed at the end of the test.
class TempDir {
 public:
  TempDir() {
    std::string pattern = (std::filesystem::temp_directory_path() / "pintag-label-XXXXXX").string();
    path_ = mkdtemp(pattern.data());
  }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

inline void WriteFile(const std::filesystem::path& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
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
