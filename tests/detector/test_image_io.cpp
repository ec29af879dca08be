// Loading photos: formats, EXIF orientation and focal length, the pixel limit checked before
// decoding, and hostile input returned as an error, never a crash.

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "pintag/detector/detector.hpp"
#include "pintag/detector/image_io.hpp"

namespace pintag {
namespace {

std::string TempPath(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / "pintag_test_image_io";
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

std::vector<std::uint8_t> ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Writes a w × h RGB image whose pixel (x, y) is (x, y, 0), with extra attributes.
std::string Write(const std::string& name, int w, int h,
                  const std::function<void(OIIO::ImageSpec&)>& attributes = {}) {
  const std::string path = TempPath(name);
  auto out = OIIO::ImageOutput::create(path);
  EXPECT_TRUE(out) << OIIO::geterror();
  OIIO::ImageSpec spec(w, h, 3, OIIO::TypeDesc::UINT8);
  if (attributes) attributes(spec);
  std::vector<std::uint8_t> pixels(static_cast<std::size_t>(w) * h * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      pixels[(static_cast<std::size_t>(y) * w + x) * 3] = static_cast<std::uint8_t>(x);
      pixels[(static_cast<std::size_t>(y) * w + x) * 3 + 1] = static_cast<std::uint8_t>(y);
    }
  EXPECT_TRUE(out->open(path, spec));
  EXPECT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, pixels.data()));
  out->close();
  return path;
}

TEST(ImageIo, ReadsPngJpegTiffAndWebp) {
  for (const char* ext : {"png", "jpg", "tif", "webp"}) {
    const std::string optional_format = ext;
    if (optional_format == "webp" &&
        !OIIO::ImageOutput::create(TempPath(std::string("probe.") + ext))) {
      continue;  // this OpenImageIO build cannot write it; reading is still wired
    }
    const std::string path = Write(std::string("small.") + ext, 40, 30);
    const LoadResult r = LoadImageFile(path);
    ASSERT_TRUE(r.image) << ext << ": " << r.error;
    EXPECT_EQ(r.image->bgr.cols, 40);
    EXPECT_EQ(r.image->bgr.rows, 30);
    EXPECT_EQ(r.image->bgr.type(), CV_8UC3);
    EXPECT_NEAR(r.image->bgr.at<cv::Vec3b>(20, 30)[2], 30, 4) << ext;  // red = x
  }
}

TEST(ImageIo, AppliesExifOrientationAndKeepsFocalLength) {
  const std::string path = Write("rotated.jpg", 40, 30, [](OIIO::ImageSpec& spec) {
    spec.attribute("Orientation", 6);  // stored rotated: display turns it 90° clockwise
    spec.attribute("Exif:FocalLengthIn35mmFilm", 28);
    spec.attribute("Exif:FocalLength", 4.5f);
  });
  const LoadResult r = LoadImageFile(path);
  ASSERT_TRUE(r.image) << r.error;
  EXPECT_EQ(r.image->exif_orientation, 6);
  EXPECT_EQ(r.image->bgr.cols, 30);
  EXPECT_EQ(r.image->bgr.rows, 40);
  // Rotating clockwise puts the stored bottom-left pixel (x 0, y 29) at the top-left.
  EXPECT_NEAR(r.image->bgr.at<cv::Vec3b>(0, 0)[1], 29, 4);
  ASSERT_TRUE(r.image->exif.focal_length_35mm);
  EXPECT_EQ(*r.image->exif.focal_length_35mm, 28);
  const DetectResult d = Detector().detect(*r.image);
  EXPECT_EQ(d.intrinsics_source, IntrinsicsSource::kExif);
}

TEST(ImageIo, PixelLimitCheckedFromTheHeader) {
  const std::string path = Write("big.png", 400, 300);
  const LoadResult r = LoadImageFile(path, 100000);
  EXPECT_FALSE(r.image);
  EXPECT_NE(r.error.find("too large"), std::string::npos) << r.error;
  EXPECT_TRUE(LoadImageFile(path, 120000).image);
}

TEST(ImageIo, BadInputIsAnErrorNeverACrash) {
  EXPECT_FALSE(LoadImageBytes({}).image);
  const std::string text = "this is not an image at all, just some text";
  EXPECT_FALSE(
      LoadImageBytes({reinterpret_cast<const std::uint8_t*>(text.data()), text.size()}).image);
  EXPECT_FALSE(LoadImageFile(TempPath("does-not-exist.jpg")).image);

  // Truncated JPEG and PNG: every prefix length class, none may crash.
  for (const char* ext : {"jpg", "png"}) {
    const std::vector<std::uint8_t> full = ReadAll(Write(std::string("full.") + ext, 64, 48));
    for (std::size_t n : {std::size_t{2}, std::size_t{3}, std::size_t{10}, full.size() / 4,
                          full.size() / 2, full.size() - 10}) {
      const LoadResult r = LoadImageBytes({full.data(), n});
      if (r.image) {
        EXPECT_TRUE(Detector().detect(*r.image).detections.empty());
      }
    }
    // Magic bytes followed by garbage.
    std::vector<std::uint8_t> junk(full.begin(), full.begin() + 8);
    junk.resize(500, 0xAB);
    const LoadResult r = LoadImageBytes(junk);
    if (r.image) {
      EXPECT_TRUE(Detector().detect(*r.image).detections.empty());
    }
  }
}

TEST(ImageIo, DegenerateSizes) {
  for (auto [w, h] : {std::pair{1, 1}, {100000, 1}, {1, 100000}}) {
    const std::string path =
        Write("thin_" + std::to_string(w) + "x" + std::to_string(h) + ".png", w, h);
    const LoadResult r = LoadImageFile(path);
    ASSERT_TRUE(r.image) << r.error;
    const DetectResult d = Detector().detect(*r.image);
    EXPECT_TRUE(d.error.empty());
    EXPECT_TRUE(d.detections.empty());
  }
}

}  // namespace
}  // namespace pintag
