// Loading photos: formats, EXIF orientation and focal length, the pixel limit checked before
// decoding, and hostile input returned as an error, never a crash.

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <malloc.h>
#include <turbojpeg.h>
#include <unistd.h>

#include <array>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <streambuf>

#include "pintag/codec/tag_raster.hpp"
#include "pintag/detector/detector.hpp"
#include "pintag/detector/image_io.hpp"

namespace pintag {
namespace {

// One scratch directory per test process, removed when it ends, so that runs side by side
// (build/ and build-sanitize/, other users) never share or leave files.
std::string TempPath(const std::string& name) {
  static const struct Scratch {
    std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                ("pintag_test_image_io-" + std::to_string(::getpid()));
    Scratch() {
      std::filesystem::remove_all(dir);
      std::filesystem::create_directories(dir);
    }
    Scratch(const Scratch&) = delete;
    Scratch& operator=(const Scratch&) = delete;
    ~Scratch() {
      std::error_code ignored;
      std::filesystem::remove_all(dir, ignored);
    }
  } scratch;
  return (scratch.dir / name).string();
}

std::vector<std::uint8_t> ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Writes a w × h RGB image whose pixel (x, y) is (x, y, 0), with extra attributes.
std::string Write(const std::string& name, int w, int h,
                  const std::function<void(OIIO::ImageSpec&)>& attributes = {}) {
  std::string path = TempPath(name);
  auto out = OIIO::ImageOutput::create(path);
  EXPECT_TRUE(out) << OIIO::geterror();
  OIIO::ImageSpec spec(w, h, 3, OIIO::TypeDesc::UINT8);
  if (attributes) attributes(spec);
  std::vector<std::uint8_t> pixels(static_cast<std::size_t>(w) * h * 3);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      pixels[(static_cast<std::size_t>(y) * w + x) * 3] = static_cast<std::uint8_t>(x);
      pixels[(static_cast<std::size_t>(y) * w + x) * 3 + 1] = static_cast<std::uint8_t>(y);
    }
  }
  EXPECT_TRUE(out->open(path, spec));
  EXPECT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, pixels.data()));
  out->close();
  return path;
}

TEST(ImageIo, ReadsPngJpegTiffAndWebp) {
  for (const char* ext : {"png", "jpg", "tif", "webp"}) {
    // Debian 12's OpenImageIO writes all four; a build that cannot is a different machine.
    ASSERT_TRUE(OIIO::ImageOutput::create(TempPath(std::string("probe.") + ext)))
        << "this OpenImageIO cannot write ." << ext;
    const std::string path = Write(std::string("small.") + ext, 40, 30);
    const LoadResult r = LoadImageFile(path);
    ASSERT_TRUE(r.image) << ext << ": " << r.error;
    EXPECT_EQ(r.image->bgr.cols, 40);
    EXPECT_EQ(r.image->bgr.rows, 30);
    EXPECT_EQ(r.image->bgr.type(), CV_8UC3);
    EXPECT_NEAR(r.image->bgr.at<cv::Vec3b>(20, 30)[2], 30, 4) << ext;  // red = x
  }
}

// PNG is read in its native type (8-bit straight, deeper as rows a few MB at a time), not through
// OpenImageIO's 64 MB conversion buffer; TIFF through that buffer. Either way the pixels must be
// exactly what OpenImageIO's own 8-bit read gives, across chunk boundaries (tall16.png: two
// chunks) and for TIFF strips.
TEST(ImageIo, PngAndTiffPixelsAreOpenImageIosOwn) {
  struct Case {
    const char* name;
    OIIO::TypeDesc type;
    int width, height;
    int rows_per_strip;  // TIFF only; 0: the writer's choice
  };
  const Case cases[] = {{"plain8.png", OIIO::TypeDesc::UINT8, 300, 200, 0},
                        {"plain8.tif", OIIO::TypeDesc::UINT8, 500, 300, 16},
                        {"deep16.png", OIIO::TypeDesc::UINT16, 300, 200, 0},
                        {"tall16.png", OIIO::TypeDesc::UINT16, 700, 1500, 0},
                        {"deep16.tif", OIIO::TypeDesc::UINT16, 1100, 900, 7},
                        {"float.tif", OIIO::TypeDesc::FLOAT, 1200, 1000, 0},
                        {"tall16.tif", OIIO::TypeDesc::UINT16, 700, 1500, 1000}};
  for (const Case& c : cases) {
    const std::string path = Write(c.name, c.width, c.height, [&](OIIO::ImageSpec& spec) {
      spec.set_format(c.type);
      if (c.rows_per_strip > 0) spec.attribute("tiff:RowsPerStrip", c.rows_per_strip);
    });
    auto reference_input = OIIO::ImageInput::open(path);
    ASSERT_TRUE(reference_input) << c.name << ": " << OIIO::geterror();
    ASSERT_EQ(reference_input->spec().format, c.type) << c.name;
    std::vector<std::uint8_t> reference(static_cast<std::size_t>(c.width) * c.height * 3);
    ASSERT_TRUE(reference_input->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, reference.data()));
    const LoadResult r = LoadImageFile(path);
    ASSERT_TRUE(r.image) << c.name << ": " << r.error;
    ASSERT_EQ(r.image->bgr.size(), cv::Size(c.width, c.height)) << c.name;
    int differing = 0;
    for (int y = 0; y < c.height; ++y) {
      for (int x = 0; x < c.width; ++x) {
        const std::uint8_t* want = &reference[(static_cast<std::size_t>(y) * c.width + x) * 3];
        const cv::Vec3b got = r.image->bgr.at<cv::Vec3b>(y, x);
        differing += got[2] != want[0] || got[1] != want[1] || got[0] != want[2];
      }
    }
    EXPECT_EQ(differing, 0) << c.name;
    // Not a constant image: the writer's gradient survived (red = x mod 256, green = y mod 256).
    EXPECT_EQ(r.image->bgr.at<cv::Vec3b>(c.height - 1, 77)[2], 77) << c.name;
    EXPECT_EQ(r.image->bgr.at<cv::Vec3b>(c.height - 1, 77)[1], (c.height - 1) % 256) << c.name;
  }
}

// BigTIFF (64-bit offsets; what some scanners and microscopes write) is a TIFF: the same pixels as
// the classic file, and every truncation is corrupt.
TEST(ImageIo, BigTiffIsReadAsTiff) {
  const std::string classic = Write("classic.tif", 300, 200);
  const std::string big =
      Write("big.tif", 300, 200, [](OIIO::ImageSpec& spec) { spec.attribute("tiff:bigtiff", 1); });
  const std::vector<std::uint8_t> bytes = ReadAll(big);
  ASSERT_EQ(bytes[2], 43) << "OpenImageIO wrote a classic TIFF";
  EXPECT_EQ(SniffImageFormat(bytes), ImageFormat::kTiff);
  const LoadResult want = LoadImageFile(classic);
  const LoadResult got = LoadImageBytes(bytes);
  ASSERT_TRUE(want.image) << want.error;
  ASSERT_TRUE(got.image) << got.error;
  EXPECT_EQ(cv::norm(got.image->bgr, want.image->bgr, cv::NORM_INF), 0);
  for (std::size_t keep = 16; keep + 1 < bytes.size(); keep += 4099) {
    EXPECT_EQ(LoadImageBytes({bytes.data(), keep}).kind, ImageError::kCorrupt) << "cut at " << keep;
  }
}

// PNG's chunk checksum (CRC-32, ISO 3309), for a hand-made chunk.
std::uint32_t PngCrc(const std::uint8_t* data, std::size_t size) {
  std::uint32_t crc = 0xFFFFFFFFU;
  for (std::size_t i = 0; i < size; ++i) {
    crc ^= data[i];
    for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ (0xEDB88320U & (0U - (crc & 1U)));
  }
  return crc ^ 0xFFFFFFFFU;
}

// A PNG's oFFs chunk sets where its rows start; near INT_MAX, the last row's number does not fit
// an int. Such a file is refused as corrupt, never read as rows that wrap around.
TEST(ImageIo, RowOffsetsNearIntMaxAreRefused) {
  for (const OIIO::TypeDesc type : {OIIO::TypeDesc::UINT8, OIIO::TypeDesc::UINT16}) {
    std::vector<std::uint8_t> png =
        ReadAll(Write("offset.png", 40, 30, [&](OIIO::ImageSpec& spec) { spec.set_format(type); }));
    // oFFs after IHDR (8-byte signature + 25-byte IHDR chunk): x 0, y INT_MAX − 10, in pixels.
    std::vector<std::uint8_t> chunk = {0, 0, 0, 9,    'o',  'F',  'F',  's', 0,
                                       0, 0, 0, 0x7F, 0xFF, 0xFF, 0xF5, 0};
    const std::uint32_t crc = PngCrc(chunk.data() + 4, chunk.size() - 4);
    for (int shift = 24; shift >= 0; shift -= 8) {
      chunk.push_back(static_cast<std::uint8_t>(crc >> shift));
    }
    png.insert(png.begin() + 33, chunk.begin(), chunk.end());
    const std::string path = TempPath("offset.png");
    std::ofstream(path, std::ios::binary)
        .write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
    auto probe = OIIO::ImageInput::open(path);
    ASSERT_TRUE(probe) << OIIO::geterror();
    ASSERT_EQ(probe->spec().y, std::numeric_limits<int>::max() - 10);  // the chunk is read
    const LoadResult r = LoadImageFile(path);
    EXPECT_FALSE(r.image) << type;
    EXPECT_EQ(r.kind, ImageError::kCorrupt) << type << ": " << r.error;
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
  EXPECT_EQ(r.kind, ImageError::kTooLarge) << r.error;
  EXPECT_EQ(r.claimed_width, 400);
  EXPECT_EQ(r.claimed_height, 300);
  EXPECT_NE(r.error.find("400 x 300"), std::string::npos) << r.error;
  EXPECT_TRUE(LoadImageFile(path, 120000).image);
  const LoadResult jpeg = LoadImageFile(Write("big.jpg", 400, 300), 100000);
  EXPECT_EQ(jpeg.kind, ImageError::kTooLarge) << jpeg.error;
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

std::vector<std::uint8_t> Encode(const char* ext, const cv::Mat& image,
                                 const std::vector<int>& params = {}) {
  std::vector<std::uint8_t> bytes;
  EXPECT_TRUE(cv::imencode(ext, image, bytes, params));
  return bytes;
}

/// A phone-like frame: smooth shading, sharp coloured edges and sensor noise, so the JPEG has both
/// flat and busy blocks and the 4:2:0 chroma upsampling matters.
cv::Mat PhoneLikeFrame(int width, int height) {
  cv::Mat image(height, width, CV_8UC3);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      image.at<cv::Vec3b>(y, x) = {static_cast<std::uint8_t>(x * 255 / width),
                                   static_cast<std::uint8_t>(y * 255 / height),
                                   static_cast<std::uint8_t>(((x / 37 + y / 23) % 2) * 200 + 30)};
    }
  }
  cv::Mat noise(height, width, CV_8UC3);
  // A generator of its own: the global one's state depends on which tests ran before.
  cv::RNG rng(20261205);
  rng.fill(noise, cv::RNG::NORMAL, 0, 6);
  cv::add(image, noise, image);
  return image;
}

TEST(ImageIo, ErrorsAreTypedNotToldByTheirText) {
  EXPECT_EQ(LoadImageBytes({}).kind, ImageError::kUnsupported);
  const std::string gif = "GIF89a not supported";
  EXPECT_EQ(LoadImageBytes({reinterpret_cast<const std::uint8_t*>(gif.data()), gif.size()}).kind,
            ImageError::kUnsupported);
  EXPECT_EQ(LoadImageFile(TempPath("does-not-exist.jpg")).kind, ImageError::kUnreadable);
  const std::vector<std::uint8_t> tiff = Encode(".tiff", PhoneLikeFrame(10, 10));
  EXPECT_EQ(SniffImageFormat(tiff), ImageFormat::kTiff);
  const LoadResult ok = LoadImageBytes(Encode(".jpg", PhoneLikeFrame(64, 48)));
  EXPECT_EQ(ok.kind, ImageError::kNone);
  ASSERT_TRUE(ok.image);
  EXPECT_EQ(ok.image->format, "jpeg");
}

// A cut upload would otherwise decode with a grey (JPEG) or black (PNG) bottom and be read as a
// partial photo.
TEST(ImageIo, EveryTruncationIsCorrupt) {
  for (const char* ext : {".jpg", ".png", ".tiff", ".webp"}) {
    const std::vector<std::uint8_t> whole = Encode(ext, PhoneLikeFrame(64, 48));
    // From 16 bytes: a WebP is told from other files by its first 12.
    for (std::size_t n = 16; n + 1 < whole.size(); n += 7) {
      const LoadResult r = LoadImageBytes({whole.data(), n});
      EXPECT_FALSE(r.image) << ext << " cut at " << n << " of " << whole.size();
      EXPECT_EQ(r.kind, ImageError::kCorrupt) << ext << " cut at " << n << ": " << r.error;
    }
  }
}

// Decoding costs memory and time per channel, which the pixel limit does not count: a header of a
// few hundred bytes declaring a thousand channels took a second and about 1.5 GB per megapixel.
// A photo has at most four (grey, grey and alpha, RGB, RGBA).
TEST(ImageIo, ImagesWithMoreThanFourChannelsAreRefusedUndecoded) {
  for (const int channels : {1, 2, 4, 5, 64, 1024}) {
    const std::string path = TempPath("channels" + std::to_string(channels) + ".tif");
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out) << OIIO::geterror();
    const OIIO::ImageSpec spec(16, 8, channels, OIIO::TypeDesc::UINT8);
    const std::vector<std::uint8_t> pixels(std::size_t{16} * 8 * static_cast<std::size_t>(channels),
                                           200);
    ASSERT_TRUE(out->open(path, spec)) << out->geterror();
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, pixels.data()));
    out->close();
    int decodes = 0;
    LoadOptions options;
    options.before_decode = [&](int, int) { ++decodes; };
    const LoadResult r = LoadImageBytes(ReadAll(path), options);
    if (channels <= 4) {
      ASSERT_TRUE(r.image) << channels << " channels: " << r.error;
      EXPECT_EQ(r.image->bgr.size(), cv::Size(16, 8));
      EXPECT_EQ(decodes, 1);
    } else {
      EXPECT_FALSE(r.image) << channels << " channels";
      EXPECT_EQ(r.kind, ImageError::kUnsupported) << channels << " channels: " << r.error;
      EXPECT_NE(r.error.find(std::to_string(channels) + " channels"), std::string::npos) << r.error;
      EXPECT_EQ(decodes, 0) << channels << " channels";
    }
  }
}

/// A little-endian TIFF written by hand: its header (first directory at 8), then what the test
/// puts: 16- and 32-bit values and 12-byte directory entries.
struct HandMadeTiff {
  std::vector<std::uint8_t> bytes = {'I', 'I', 42, 0, 8, 0, 0, 0};
  void put16(std::uint32_t v) {
    bytes.push_back(static_cast<std::uint8_t>(v));
    bytes.push_back(static_cast<std::uint8_t>(v >> 8));
  }
  void put32(std::uint32_t v) {
    put16(v & 0xFFFFU);
    put16(v >> 16);
  }
  void entry(std::uint32_t tag, std::uint32_t type, std::uint32_t count, std::uint32_t value) {
    put16(tag), put16(type), put32(count), put32(value);
  }
};

// A TIFF whose directory comes before its pixels still opens when the pixels are cut off;
// OpenImageIO then reports the missing rows only as errors left pending, one per row.
TEST(ImageIo, ATiffCutOffAfterItsDirectoryIsCorrupt) {
  constexpr std::uint32_t kWidth = 64, kHeight = 48;
  HandMadeTiff t;
  std::vector<std::uint8_t>& tiff = t.bytes;
  const auto put32 = [&](std::uint32_t v) { t.put32(v); };
  const auto entry = [&](std::uint32_t tag, std::uint32_t type, std::uint32_t count,
                         std::uint32_t value) { t.entry(tag, type, count, value); };
  // Grey, 8 bits, uncompressed, one row per strip: each strip's offset and size in two arrays.
  constexpr std::uint32_t kEntries = 8;
  constexpr std::uint32_t kOffsets = 8 + 2 + (12 * kEntries) + 4;
  constexpr std::uint32_t kCounts = kOffsets + (4 * kHeight);
  constexpr std::uint32_t kPixels = kCounts + (4 * kHeight);
  t.put16(kEntries);
  entry(256, 4, 1, kWidth);          // ImageWidth
  entry(257, 4, 1, kHeight);         // ImageLength
  entry(258, 3, 1, 8);               // BitsPerSample
  entry(259, 3, 1, 1);               // Compression: none
  entry(262, 3, 1, 1);               // PhotometricInterpretation: black is zero
  entry(273, 4, kHeight, kOffsets);  // StripOffsets
  entry(278, 4, 1, 1);               // RowsPerStrip
  entry(279, 4, kHeight, kCounts);   // StripByteCounts
  put32(0);                          // no next directory
  for (std::uint32_t row = 0; row < kHeight; ++row) put32(kPixels + (row * kWidth));
  for (std::uint32_t row = 0; row < kHeight; ++row) put32(kWidth);
  for (std::uint32_t i = 0; i < kWidth * kHeight; ++i) tiff.push_back(static_cast<std::uint8_t>(i));
  ASSERT_EQ(tiff.size(), kPixels + (kWidth * kHeight));

  const LoadResult whole = LoadImageBytes(tiff);
  ASSERT_TRUE(whole.image) << whole.error;
  EXPECT_EQ(whole.image->bgr.at<cv::Vec3b>(1, 3), cv::Vec3b(67, 67, 67));  // row 1, column 3

  for (const std::size_t keep :
       {std::size_t{kPixels}, std::size_t{kPixels} + (kWidth * kHeight / 2)}) {
    const LoadResult cut = LoadImageBytes({tiff.data(), keep});
    EXPECT_FALSE(cut.image) << "cut at " << keep;
    EXPECT_EQ(cut.kind, ImageError::kCorrupt) << "cut at " << keep;
    // One line however many rows are missing: the message becomes an HTTP answer's detail.
    EXPECT_EQ(cut.error.find('\n'), std::string::npos) << cut.error.substr(0, 400);
    EXPECT_LT(cut.error.size(), 300U) << cut.error.substr(0, 400);
  }
}

TEST(ImageIo, UnusualButWholeJpegsLoad) {
  const cv::Mat frame = PhoneLikeFrame(200, 100);
  for (const std::vector<int>& params :
       {std::vector<int>{cv::IMWRITE_JPEG_PROGRESSIVE, 1},
        std::vector<int>{cv::IMWRITE_JPEG_RST_INTERVAL, 2}, std::vector<int>{}}) {
    std::vector<std::uint8_t> jpeg = Encode(".jpg", frame, params);
    jpeg.insert(jpeg.end(), 100, 0x55);  // some phones append data after the end of the image
    const LoadResult r = LoadImageBytes(jpeg);
    ASSERT_TRUE(r.image) << r.error;
    EXPECT_EQ(r.image->bgr.cols, 200);
  }
}

std::size_t FindMarker(const std::vector<std::uint8_t>& jpeg, std::uint8_t marker) {
  for (std::size_t i = 0; i + 1 < jpeg.size(); ++i) {
    if (jpeg[i] == 0xFF && jpeg[i + 1] == marker) return i;
  }
  ADD_FAILURE() << "no marker 0xFF" << std::hex << int{marker};
  return 0;
}

bool SamePixels(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

// A JFIF header of version 2.01 (some scanners' software) is a libjpeg warning, which is
// otherwise refused (truncation is only a warning): such a file decodes to exactly the pixels of
// the same file at version 1.
// Stray bytes between the last scan and the end marker are not accepted the same way: when
// libjpeg warns of them (it reads some into its bit buffer unwarned), a cut file followed by
// bytes and an end marker gives the same warning whenever the decoder took those bytes as its
// missing data. That was found at two cut points of a progressive photo while they were accepted.
TEST(ImageIo, JpegsWithAJfifVersionOtherThanOneLoad) {
  for (const bool progressive : {false, true}) {
    const std::vector<std::uint8_t> clean = Encode(
        ".jpg", PhoneLikeFrame(200, 120), {cv::IMWRITE_JPEG_PROGRESSIVE, progressive ? 1 : 0});
    const LoadResult reference = LoadImageBytes(clean);
    ASSERT_TRUE(reference.image) << reference.error;
    const JpegPlanesResult reference_planes = LoadJpegPlanes(clean);
    ASSERT_TRUE(reference_planes.planes) << reference_planes.error;

    std::vector<std::uint8_t> jfif2 = clean;
    const std::size_t jfif = FindMarker(jfif2, 0xE0) + 4;
    ASSERT_EQ(std::string(jfif2.begin() + jfif, jfif2.begin() + jfif + 5),
              std::string("JFIF\0", 5));
    jfif2[jfif + 5] = 2;
    jfif2[jfif + 6] = 1;
    const LoadResult r = LoadImageBytes(jfif2);
    ASSERT_TRUE(r.image) << "progressive " << progressive << ": " << r.error;
    EXPECT_TRUE(SamePixels(r.image->bgr, reference.image->bgr));
    EXPECT_EQ(r.image->chroma_upsampling, reference.image->chroma_upsampling);
    const JpegPlanesResult planes = LoadJpegPlanes(jfif2);
    ASSERT_TRUE(planes.planes) << planes.error;
    EXPECT_TRUE(SamePixels(planes.planes->y, reference_planes.planes->y));
    EXPECT_TRUE(SamePixels(planes.planes->cr, reference_planes.planes->cr));
  }
}

// JPEGs no camera writes, which libjpeg-turbo cannot decode: 12-bit samples, lossless and
// hierarchical coding. Their start-of-frame marker says so: unsupported, not corrupt.
TEST(ImageIo, LosslessHierarchicalAndTwelveBitJpegsAreUnsupported) {
  const std::vector<std::uint8_t> clean = Encode(".jpg", PhoneLikeFrame(64, 48));
  const std::size_t frame = FindMarker(clean, 0xC0);
  struct Case {
    const char* name;
    std::uint8_t marker;
    std::uint8_t precision;
    const char* says;
  };
  for (const Case& c :
       {Case{"12-bit", 0xC1, 12, "12-bit"}, Case{"16-bit", 0xC2, 16, "16-bit"},
        Case{"lossless", 0xC3, 8, "lossless"}, Case{"arithmetic lossless", 0xCB, 8, "lossless"},
        Case{"hierarchical", 0xC5, 8, "hierarchical"}}) {
    std::vector<std::uint8_t> bytes = clean;
    bytes[frame + 1] = c.marker;
    bytes[frame + 4] = c.precision;
    for (const ImageError kind : {LoadImageBytes(bytes).kind, LoadJpegPlanes(bytes).kind}) {
      EXPECT_EQ(kind, ImageError::kUnsupported) << c.name;
    }
    EXPECT_NE(LoadImageBytes(bytes).error.find(c.says), std::string::npos)
        << c.name << ": " << LoadImageBytes(bytes).error;
  }
  // SOF1 (extended sequential) at 8 bits is what some encoders write for ordinary photos.
  std::vector<std::uint8_t> extended = clean;
  extended[frame + 1] = 0xC1;
  EXPECT_TRUE(LoadImageBytes(extended).image) << LoadImageBytes(extended).error;
}

// Writes `values` (width × height × channels, 8-bit; WebP: RGBA only) with OpenImageIO, or
// OpenCV for WebP; `associated`: a TIFF whose colour is stored multiplied by alpha.
std::string WriteWithAlpha(const std::string& name, int width, int height, int channels,
                           const std::vector<std::uint8_t>& values, bool associated = false) {
  std::string path = TempPath(name);
  if (name.ends_with(".webp")) {  // lossless, which OpenCV writes at quality above 100
    cv::Mat rgba(height, width, CV_8UC4);
    std::copy(values.begin(), values.end(), rgba.data);
    cv::Mat bgra;
    cv::cvtColor(rgba, bgra, cv::COLOR_RGBA2BGRA);
    EXPECT_TRUE(cv::imwrite(path, bgra, {cv::IMWRITE_WEBP_QUALITY, 101}));
    return path;
  }
  auto out = OIIO::ImageOutput::create(path);
  EXPECT_TRUE(out) << OIIO::geterror();
  OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::UINT8);
  spec.alpha_channel = channels - 1;
  if (!associated) spec.attribute("oiio:UnassociatedAlpha", 1);
  EXPECT_TRUE(out->open(path, spec)) << out->geterror();
  EXPECT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, values.data())) << out->geterror();
  out->close();
  return path;
}

// A label or tag exported with a transparent background shows on a page, and prints, over white:
// it is read so. Its transparent pixels' stored colour (often black) must not show through.
TEST(ImageIo, TransparentPixelsAreCompositedOverWhite) {
  // Three pixels, RGBA: transparent black, opaque orange, orange at half alpha (128).
  const std::vector<std::uint8_t> rgba = {0, 0, 0, 0, 200, 100, 50, 255, 200, 100, 50, 128};
  // Over white: v × a / 255 + 255 × (255 − a) / 255.
  const auto over_white = [](int v, int a) { return (v * a + 255 * (255 - a)) / 255.0; };
  for (const char* name : {"alpha.png", "alpha.tif", "alpha.webp"}) {
    const LoadResult r = LoadImageFile(WriteWithAlpha(name, 3, 1, 4, rgba));
    ASSERT_TRUE(r.image) << name << ": " << r.error;
    const cv::Mat& bgr = r.image->bgr;
    EXPECT_EQ(bgr.at<cv::Vec3b>(0, 0), cv::Vec3b(255, 255, 255)) << name;
    EXPECT_EQ(bgr.at<cv::Vec3b>(0, 1), cv::Vec3b(50, 100, 200)) << name;
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(bgr.at<cv::Vec3b>(0, 2)[2 - c], over_white(rgba[8 + c], 128), 1.0)
          << name << ", channel " << c;
    }
  }
  // A TIFF that stores colour multiplied by alpha: the half-transparent pixel holds half of it.
  const std::vector<std::uint8_t> associated = {0, 0, 0, 0, 200, 100, 50, 255, 100, 50, 25, 128};
  const LoadResult tiff =
      LoadImageFile(WriteWithAlpha("associated.tif", 3, 1, 4, associated, true));
  ASSERT_TRUE(tiff.image) << tiff.error;
  EXPECT_EQ(tiff.image->bgr.at<cv::Vec3b>(0, 0), cv::Vec3b(255, 255, 255));
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(tiff.image->bgr.at<cv::Vec3b>(0, 2)[2 - c], over_white(rgba[8 + c], 128), 1.0)
        << "associated, channel " << c;
  }
  // Grey and alpha.
  const LoadResult grey = LoadImageFile(WriteWithAlpha("grey-alpha.png", 2, 1, 2, {0, 0, 90, 255}));
  ASSERT_TRUE(grey.image) << grey.error;
  EXPECT_EQ(grey.image->bgr.at<cv::Vec3b>(0, 0), cv::Vec3b(255, 255, 255));
  EXPECT_EQ(grey.image->bgr.at<cv::Vec3b>(0, 1), cv::Vec3b(90, 90, 90));
}

// The real tag, its white (quiet zone and light elements' surround) made transparent black, on a
// transparent canvas: read as the same tag.
TEST(ImageIo, ATagWithATransparentBackgroundIsRead) {
  const TagKey key(11684);
  const TagRaster tag = RenderTagRaster(key, {.square_px = 160});
  const int width = 480;
  const int height = 360;
  std::vector<std::uint8_t> rgba(static_cast<std::size_t>(width) * height * 4, 0);
  int transparent = 0;
  for (int y = 0; y < tag.image.height; ++y) {
    for (int x = 0; x < tag.image.width; ++x) {
      const Rgb8 p = tag.image.at(x, y);
      const bool white = p.r > 200 && p.g > 200 && p.b > 200;
      transparent += white;
      const std::size_t i = (static_cast<std::size_t>(y + 60) * width + x + 120) * 4;
      if (!white) rgba[i] = p.r, rgba[i + 1] = p.g, rgba[i + 2] = p.b, rgba[i + 3] = 255;
    }
  }
  ASSERT_GT(transparent, tag.image.width * 4) << "the quiet zone is white";
  for (const char* name : {"tag-alpha.png", "tag-alpha.webp"}) {
    const LoadResult r = LoadImageFile(WriteWithAlpha(name, width, height, 4, rgba));
    ASSERT_TRUE(r.image) << name << ": " << r.error;
    const DetectResult found = Detector().detect(*r.image);
    ASSERT_EQ(found.detections.size(), 1U) << name;
    ASSERT_TRUE(found.detections[0].key) << name;
    EXPECT_EQ(found.detections[0].key->value(), key.value()) << name;
  }
}

// libjpeg-turbo straight to BGR against OpenCV's own JPEG reader: the same pixels within rounding.
TEST(ImageIo, JpegPixelsMatchOpenCv) {
  for (int quality : {75, 95}) {
    const std::vector<std::uint8_t> jpeg =
        Encode(".jpg", PhoneLikeFrame(640, 360), {cv::IMWRITE_JPEG_QUALITY, quality});
    const LoadResult r = LoadImageBytes(jpeg);
    ASSERT_TRUE(r.image) << r.error;
    const cv::Mat reference = cv::imdecode(jpeg, cv::IMREAD_COLOR);
    ASSERT_EQ(r.image->bgr.size(), reference.size());
    cv::Mat diff;
    cv::absdiff(r.image->bgr, reference, diff);
    double max_diff = 0;
    cv::minMaxLoc(diff.reshape(1), nullptr, &max_diff);
    EXPECT_LE(max_diff, 2) << "quality " << quality;
    EXPECT_LT(cv::mean(diff)[0], 0.5) << "quality " << quality;
  }
}

// Every EXIF orientation, written into a real JPEG by OpenImageIO, gives the upright image that
// OpenCV's reader (which also applies EXIF orientation) gives.
TEST(ImageIo, EveryExifOrientationMatchesOpenCv) {
  for (int orientation = 1; orientation <= 8; ++orientation) {
    const std::string path =
        Write("oriented" + std::to_string(orientation) + ".jpg", 40, 30,
              [orientation](OIIO::ImageSpec& spec) { spec.attribute("Orientation", orientation); });
    const LoadResult r = LoadImageFile(path);
    ASSERT_TRUE(r.image) << r.error;
    EXPECT_EQ(r.image->exif_orientation, orientation);
    const cv::Mat reference = cv::imread(path, cv::IMREAD_COLOR);
    ASSERT_EQ(r.image->bgr.size(), reference.size()) << orientation;
    cv::Mat diff;
    cv::absdiff(r.image->bgr, reference, diff);
    double max_diff = 0;
    cv::minMaxLoc(diff.reshape(1), nullptr, &max_diff);
    EXPECT_LE(max_diff, 2) << "orientation " << orientation;
  }
}

// The server's pixel budget waits in this hook: it must come once per decoded photo, with the
// stored size, and never for a photo refused before decoding (no budget held for nothing).
TEST(ImageIo, BeforeDecodeIsToldTheSizeOnceAndOnlyForPhotosThatAreDecoded) {
  std::vector<std::pair<int, int>> told;
  LoadOptions options;
  options.before_decode = [&](int width, int height) { told.emplace_back(width, height); };
  for (const char* ext : {".jpg", ".png", ".tiff", ".webp"}) {
    told.clear();
    const LoadResult loaded = LoadImageBytes(Encode(ext, PhoneLikeFrame(64, 48)), options);
    ASSERT_TRUE(loaded.image.has_value()) << ext << ": " << loaded.error;
    ASSERT_EQ(told.size(), 1U) << ext;
    EXPECT_EQ(told[0], std::make_pair(64, 48)) << ext;
  }
  options.max_pixels = 64 * 48 - 1;
  for (const char* ext : {".jpg", ".png", ".tiff", ".webp"}) {
    told.clear();
    EXPECT_EQ(LoadImageBytes(Encode(ext, PhoneLikeFrame(64, 48)), options).kind,
              ImageError::kTooLarge)
        << ext;
    EXPECT_TRUE(told.empty()) << ext;
  }
  options.max_pixels = kDefaultMaxPixels;
  told.clear();
  std::vector<std::uint8_t> cut = Encode(".png", PhoneLikeFrame(64, 48));
  cut.resize(cut.size() / 2);
  EXPECT_EQ(LoadImageBytes(cut, options).kind, ImageError::kCorrupt);
  EXPECT_TRUE(told.empty());
}

/// A CMYK JPEG (print workflows): TurboJPEG encodes it, OpenImageIO decodes it.
std::vector<std::uint8_t> CmykJpeg(int width, int height) {
  std::vector<std::uint8_t> cmyk(static_cast<std::size_t>(width) * height * 4);
  for (std::size_t i = 0; i < cmyk.size(); ++i) cmyk[i] = static_cast<std::uint8_t>(i * 7 % 251);
  tjhandle tj = tjInitCompress();
  unsigned char* jpeg = nullptr;
  unsigned long size = 0;
  const int failed =
      tjCompress2(tj, cmyk.data(), width, 0, height, TJPF_CMYK, &jpeg, &size, TJSAMP_444, 90, 0);
  std::vector<std::uint8_t> bytes;
  if (failed == 0) bytes.assign(jpeg, jpeg + size);
  tjFree(jpeg);
  tjDestroy(tj);
  EXPECT_EQ(failed, 0);
  return bytes;
}

#if !defined(__SANITIZE_ADDRESS__)
// Bytes the heap holds now, in small blocks and in mmapped large ones.
std::size_t HeapInUse() {
  const struct mallinfo2 m = mallinfo2();
  return m.uordblks + m.hblkhd;
}

// The server waits for memory in before_decode, so no decoder may have made the photo's pixels by
// then: the heap may grow by far less than the 2.4 MB of BGR a 1000 x 800 photo decodes to, and
// must have grown by that much once it is loaded (else the heap is not being seen at all).
// (OpenImageIO decodes a whole WebP while opening it; it was once told after that.) ASan's
// allocator is invisible to mallinfo2, so the sanitizer build leaves this test out.
TEST(ImageIo, BeforeDecodeComesBeforeAnyPixelIsDecoded) {
  const cv::Mat frame = PhoneLikeFrame(1000, 800);
  const std::vector<std::pair<std::string, std::vector<std::uint8_t>>> photos = {
      {"jpeg", Encode(".jpg", frame)},
      {"png", Encode(".png", frame)},
      {"tiff", Encode(".tiff", frame)},
      {"webp", Encode(".webp", frame)},
      {"lossless webp", Encode(".webp", frame, {cv::IMWRITE_WEBP_QUALITY, 101})},
      {"cmyk jpeg", CmykJpeg(1000, 800)}};
  for (const auto& photo : photos) {
    const std::string& name = photo.first;
    const std::vector<std::uint8_t>& bytes = photo.second;
    std::size_t at_call = 0;
    int calls = 0;
    LoadOptions options;
    options.before_decode = [&](int width, int height) {
      at_call = HeapInUse();
      ++calls;
      EXPECT_EQ(width, 1000) << name;
      EXPECT_EQ(height, 800) << name;
    };
    const std::size_t at_start = HeapInUse();
    const LoadResult loaded = LoadImageBytes(bytes, options);
    ASSERT_TRUE(loaded.image.has_value()) << name << ": " << loaded.error;
    EXPECT_EQ(calls, 1) << name;
    const std::size_t grown = at_call > at_start ? at_call - at_start : 0;
    EXPECT_LT(grown, std::size_t{1000} * 800) << name << ": " << grown << " bytes before the call";
    const std::size_t loaded_heap = HeapInUse();
    EXPECT_GE(loaded_heap > at_start ? loaded_heap - at_start : 0, std::size_t{1000} * 800 * 3)
        << name << ": the decoded photo is not seen on the heap";
  }
}
#endif

TEST(ImageIo, ScaledJpegDecoding) {
  const cv::Mat frame = PhoneLikeFrame(640, 360);
  const std::vector<std::uint8_t> jpeg = Encode(".jpg", frame, {cv::IMWRITE_JPEG_QUALITY, 95});
  LoadOptions options;
  options.scale_denominator = 2;
  const LoadResult r = LoadImageBytes(jpeg, options);
  ASSERT_TRUE(r.image) << r.error;
  EXPECT_EQ(r.image->bgr.cols, 320);
  EXPECT_EQ(r.image->bgr.rows, 180);
  EXPECT_EQ(r.claimed_width, 640);  // the limit applies to the stored size
  cv::Mat halved;
  cv::resize(frame, halved, {320, 180}, 0, 0, cv::INTER_AREA);
  cv::Mat diff;
  cv::absdiff(r.image->bgr, halved, diff);
  EXPECT_LT(cv::mean(diff)[0], 6);
}

TEST(ImageIo, JpegPlanesAsStored) {
  const cv::Mat frame = PhoneLikeFrame(640, 360);
  const std::vector<std::uint8_t> jpeg = Encode(".jpg", frame, {cv::IMWRITE_JPEG_QUALITY, 95});
  const JpegPlanesResult r = LoadJpegPlanes(jpeg);
  ASSERT_TRUE(r.planes) << r.error;
  EXPECT_EQ(r.planes->y.size(), cv::Size(640, 360));
  EXPECT_EQ(r.planes->cb.size(), cv::Size(320, 180));  // OpenCV writes 4:2:0
  EXPECT_EQ(r.planes->cr.size(), cv::Size(320, 180));
  cv::Mat ycrcb;
  cv::cvtColor(cv::imdecode(jpeg, cv::IMREAD_COLOR), ycrcb, cv::COLOR_BGR2YCrCb);
  cv::Mat luma;
  cv::extractChannel(ycrcb, luma, 0);
  cv::Mat diff;
  cv::absdiff(r.planes->y, luma, diff);
  EXPECT_LT(cv::mean(diff)[0], 1.5);
  const std::vector<std::uint8_t> png = Encode(".png", frame);
  EXPECT_EQ(LoadJpegPlanes(png).kind, ImageError::kUnsupported);
}

// The loader says how the decoder filled in subsampled colour, in the upright image's axes: the
// reader undoes exactly that, and nothing where the colour was stored whole.

/// A one-frame animated WebP around a still one's image chunk (RIFF: VP8X with the animation flag,
/// ANIM, then ANMF holding the frame header and the still's "VP8 " or "VP8L" chunk).
std::vector<std::uint8_t> AnimatedWebp(const std::vector<std::uint8_t>& still, int width,
                                       int height) {
  const auto le = [](std::vector<std::uint8_t>& out, std::uint32_t value, int bytes) {
    for (int i = 0; i < bytes; ++i) out.push_back(static_cast<std::uint8_t>(value >> (8 * i)));
  };
  const auto chunk = [&](std::vector<std::uint8_t>& out, const char* tag,
                         const std::vector<std::uint8_t>& payload) {
    out.insert(out.end(), tag, tag + 4);
    le(out, static_cast<std::uint32_t>(payload.size()), 4);
    out.insert(out.end(), payload.begin(), payload.end());
    if (payload.size() % 2 == 1) out.push_back(0);
  };
  // The still is RIFF, size, WEBP, then its one image chunk.
  const std::vector<std::uint8_t> image(still.begin() + 12, still.end());
  std::vector<std::uint8_t> vp8x = {0x02, 0, 0, 0};  // the animation flag
  le(vp8x, static_cast<std::uint32_t>(width - 1), 3);
  le(vp8x, static_cast<std::uint32_t>(height - 1), 3);
  const std::vector<std::uint8_t> anim = {0, 0, 0, 0, 0, 0};  // background, loop for ever
  std::vector<std::uint8_t> frame;
  le(frame, 0, 3);  // x / 2
  le(frame, 0, 3);  // y / 2
  le(frame, static_cast<std::uint32_t>(width - 1), 3);
  le(frame, static_cast<std::uint32_t>(height - 1), 3);
  le(frame, 100, 3);  // duration, ms
  frame.push_back(0);
  frame.insert(frame.end(), image.begin(), image.end());
  std::vector<std::uint8_t> body = {'W', 'E', 'B', 'P'};
  chunk(body, "VP8X", vp8x);
  chunk(body, "ANIM", anim);
  chunk(body, "ANMF", frame);
  std::vector<std::uint8_t> file = {'R', 'I', 'F', 'F'};
  le(file, static_cast<std::uint32_t>(body.size()), 4);
  file.insert(file.end(), body.begin(), body.end());
  return file;
}

TEST(ImageIo, ReportsTheDecodersChromaUpsampling) {
  // OpenImageIO writes 4:4:4, 4:2:2 and 4:2:0 (4:4:0 is test_tag_samples.cpp's, through
  // TurboJPEG). A mirrored stored axis of odd length puts the chroma blocks on odd pixels: not
  // modelled, so none (41 px wide: orientations 3 and 8 mirror the columns, 6 does not).
  const struct {
    const char* subsampling;
    int orientation;
    int width;
    ChromaUpsampling expected;
  } kJpegs[] = {
      {"4:2:0", 1, 40, ChromaUpsampling::kBoth}, {"4:2:2", 1, 40, ChromaUpsampling::kAcross},
      {"4:2:2", 6, 40, ChromaUpsampling::kDown}, {"4:2:2", 3, 40, ChromaUpsampling::kAcross},
      {"4:4:4", 1, 40, ChromaUpsampling::kNone}, {"4:2:0", 8, 40, ChromaUpsampling::kBoth},
      {"4:2:0", 1, 41, ChromaUpsampling::kBoth}, {"4:2:0", 3, 41, ChromaUpsampling::kNone},
      {"4:2:0", 6, 41, ChromaUpsampling::kBoth}, {"4:2:0", 8, 41, ChromaUpsampling::kNone},
  };
  for (const auto& j : kJpegs) {
    const std::string name = std::string("chroma-") + j.subsampling[2] + j.subsampling[4] + "-" +
                             std::to_string(j.orientation) + "-" + std::to_string(j.width) + ".jpg";
    const LoadResult r = LoadImageFile(Write(name, j.width, 30, [&](OIIO::ImageSpec& spec) {
      spec.attribute("jpeg:subsampling", j.subsampling);
      spec.attribute("Orientation", j.orientation);
    }));
    ASSERT_TRUE(r.image) << r.error;
    EXPECT_EQ(r.image->exif_orientation, j.orientation);
    EXPECT_EQ(r.image->chroma_upsampling, j.expected)
        << j.subsampling << " " << j.orientation << " " << j.width;
  }
  const cv::Mat frame = PhoneLikeFrame(64, 48);
  cv::Mat grey;
  cv::cvtColor(frame, grey, cv::COLOR_BGR2GRAY);
  const struct {
    const char* what;
    std::vector<std::uint8_t> bytes;
    ChromaUpsampling expected;
  } kOthers[] = {
      {"greyscale JPEG", Encode(".jpg", grey), ChromaUpsampling::kNone},
      {"PNG", Encode(".png", frame), ChromaUpsampling::kNone},
      {"lossy WebP", Encode(".webp", frame, {cv::IMWRITE_WEBP_QUALITY, 90}),
       ChromaUpsampling::kBoth},
      {"lossless WebP", Encode(".webp", frame, {cv::IMWRITE_WEBP_QUALITY, 101}),
       ChromaUpsampling::kNone},
  };
  for (const auto& o : kOthers) {
    const LoadResult r = LoadImageBytes(o.bytes);
    ASSERT_TRUE(r.image) << o.what << ": " << r.error;
    EXPECT_EQ(r.image->chroma_upsampling, o.expected) << o.what;
  }
  // An animated WebP (a phone's "live" photo saved so) decodes its first frame, lossy here: its
  // image chunk sits inside an ANMF chunk, which was not looked into ("none").
  const LoadResult animated = LoadImageBytes(AnimatedWebp(kOthers[2].bytes, 64, 48));
  ASSERT_TRUE(animated.image) << animated.error;
  EXPECT_EQ(animated.image->bgr.cols, 64);
  EXPECT_EQ(animated.image->chroma_upsampling, ChromaUpsampling::kBoth);
  EXPECT_EQ(LoadImageBytes(AnimatedWebp(kOthers[3].bytes, 64, 48)).image->chroma_upsampling,
            ChromaUpsampling::kNone);
  LoadOptions halved;
  halved.scale_denominator = 2;
  const LoadResult scaled = LoadImageBytes(Encode(".jpg", frame), halved);
  ASSERT_TRUE(scaled.image) << scaled.error;
  EXPECT_EQ(scaled.image->chroma_upsampling, ChromaUpsampling::kNone);
}

// A PNG's sides are 1 to 2^31 - 1 pixels. A header giving 0 or more was taken for a photo of
// 2147483647 x 2147483647 pixels, "too large": it is damage, and said so.
TEST(ImageIo, APngHeaderSizeNoPngCanHoldIsCorrupt) {
  const std::vector<std::uint8_t> whole = ReadAll(Write("size.png", 40, 30));
  for (const auto& [width, height] :
       {std::pair{0xFFFFFFFFU, 0xFFFFFFFFU}, std::pair{0x80000000U, 30U}, std::pair{40U, 0U}}) {
    std::vector<std::uint8_t> png = whole;
    // IHDR's data starts after the 8-byte signature, its length and its type; its CRC is mended.
    for (int i = 0; i < 4; ++i) {
      png[16 + i] = static_cast<std::uint8_t>(width >> (24 - 8 * i));
      png[20 + i] = static_cast<std::uint8_t>(height >> (24 - 8 * i));
    }
    const std::uint32_t crc = PngCrc(png.data() + 12, 17);
    for (int i = 0; i < 4; ++i) png[29 + i] = static_cast<std::uint8_t>(crc >> (24 - 8 * i));
    const LoadResult r = LoadImageBytes(png);
    EXPECT_FALSE(r.image);
    EXPECT_EQ(r.kind, ImageError::kCorrupt) << width << " x " << height << ": " << r.error;
    EXPECT_NE(r.error.find(std::to_string(width) + " x " + std::to_string(height) +
                           " pixels, outside what a PNG can hold"),
              std::string::npos)
        << r.error;
  }
}

// Where a PNG's chunk of `type` starts (its length field), or 0 when it has none.
std::size_t FindPngChunk(const std::vector<std::uint8_t>& png, const char* type) {
  for (std::size_t pos = 8; pos + 12 <= png.size();) {
    const std::size_t length = (std::size_t{png[pos]} << 24) | (std::size_t{png[pos + 1]} << 16) |
                               (std::size_t{png[pos + 2]} << 8) | png[pos + 3];
    if (std::memcmp(&png[pos + 4], type, 4) == 0) return pos;
    pos += 12 + length;
  }
  return 0;
}

// A bit flipped in a critical chunk was refused by libpng, which printed "libpng error: ..." to
// stderr first: a plain line among the server's JSON log lines. The checksum is checked before
// libpng runs, and said so; a damaged ancillary chunk is dropped, as libpng does, and the image
// read.
TEST(ImageIo, APngChunkFailingItsChecksumIsCorruptAndNamed) {
  const std::vector<std::uint8_t> whole = Encode(".png", PhoneLikeFrame(64, 48));
  const std::size_t idat = FindPngChunk(whole, "IDAT");
  ASSERT_GT(idat, 0U);
  std::vector<std::uint8_t> flipped = whole;
  flipped[idat + 8 + 5] ^= 0x10U;
  testing::internal::CaptureStderr();
  const LoadResult damaged = LoadImageBytes(flipped);
  const std::string printed = testing::internal::GetCapturedStderr();
  EXPECT_FALSE(damaged.image);
  EXPECT_EQ(damaged.kind, ImageError::kCorrupt) << damaged.error;
  EXPECT_NE(damaged.error.find("IDAT chunk fails its checksum"), std::string::npos)
      << damaged.error;
  EXPECT_EQ(printed, "");

  // A tEXt chunk after IHDR (8 + 25 bytes in), its checksum wrong by one.
  const std::string text = "Comment";
  std::vector<std::uint8_t> chunk = {0,   0,   0,   static_cast<std::uint8_t>(text.size()),
                                     't', 'E', 'X', 't'};
  chunk.insert(chunk.end(), text.begin(), text.end());
  const std::uint32_t wrong = PngCrc(chunk.data() + 4, 4 + text.size()) ^ 1U;
  for (int i = 0; i < 4; ++i) chunk.push_back(static_cast<std::uint8_t>(wrong >> (24 - 8 * i)));
  std::vector<std::uint8_t> with_text = whole;
  with_text.insert(with_text.begin() + 33, chunk.begin(), chunk.end());
  const LoadResult read = LoadImageBytes(with_text);
  const LoadResult want = LoadImageBytes(whole);
  ASSERT_TRUE(read.image) << read.error;
  ASSERT_TRUE(want.image) << want.error;
  EXPECT_EQ(cv::norm(read.image->bgr, want.image->bgr, cv::NORM_INF), 0);

  // The same chunk with a byte of its type no letter: libpng's "invalid chunk type", which it
  // printed on stderr (a docs walkthrough, 2026-12-07), is refused before libpng runs.
  std::vector<std::uint8_t> bad_type = with_text;
  bad_type[33 + 4 + 3] = 0x8C;
  testing::internal::CaptureStderr();
  const LoadResult refused = LoadImageBytes(bad_type);
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
  EXPECT_FALSE(refused.image);
  EXPECT_EQ(refused.kind, ImageError::kCorrupt) << refused.error;
  EXPECT_NE(refused.error.find("a chunk's type is 0x7445588c, not four letters"), std::string::npos)
      << refused.error;
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

// A tiled TIFF is decoded a tile at a time into a buffer of the tile's size, which the pixel
// limit did not count: a 1 KB file of a 64 x 48 image in 16384 x 16384 tiles took 1.5 GB.
TEST(ImageIo, TilesFarLargerThanTheImageAreRefusedUndecoded) {
  for (const int tile : {16, 64, 256}) {  // ordinary tiles, some larger than the image
    const std::string path =
        Write("tiled" + std::to_string(tile) + ".tif", 64, 48, [tile](OIIO::ImageSpec& spec) {
          spec.tile_width = tile;
          spec.tile_height = tile;
        });
    const LoadResult r = LoadImageBytes(ReadAll(path));
    ASSERT_TRUE(r.image) << tile << ": " << r.error;
    EXPECT_EQ(r.image->bgr.at<cv::Vec3b>(1, 3), cv::Vec3b(0, 1, 3)) << tile;  // (x, y, 0) as BGR
  }
  HandMadeTiff t;
  std::vector<std::uint8_t>& tiff = t.bytes;
  const auto entry = [&](std::uint32_t tag, std::uint32_t type, std::uint32_t count,
                         std::uint32_t value) { t.entry(tag, type, count, value); };
  constexpr std::uint32_t kEntries = 9;
  constexpr std::uint32_t kPixels = 8 + 2 + (12 * kEntries) + 4;
  t.put16(kEntries);
  entry(256, 4, 1, 64);       // ImageWidth
  entry(257, 4, 1, 48);       // ImageLength
  entry(258, 3, 1, 8);        // BitsPerSample
  entry(259, 3, 1, 1);        // Compression: none
  entry(262, 3, 1, 1);        // PhotometricInterpretation: black is zero
  entry(322, 4, 1, 16384);    // TileWidth
  entry(323, 4, 1, 16384);    // TileLength
  entry(324, 4, 1, kPixels);  // TileOffsets
  entry(325, 4, 1, 1024);     // TileByteCounts
  t.put32(0);                 // no next directory
  tiff.resize(kPixels + 1024, 0x80);
  int decodes = 0;
  LoadOptions options;
  options.before_decode = [&](int, int) { ++decodes; };
  const LoadResult bomb = LoadImageBytes(tiff, options);
  EXPECT_FALSE(bomb.image);
  EXPECT_EQ(bomb.kind, ImageError::kTooLarge) << bomb.error;
  EXPECT_NE(bomb.error.find("tiles of 16384 x 16384"), std::string::npos) << bomb.error;
  EXPECT_EQ(decodes, 0);
}

// TurboJPEG refuses a JPEG of more than 500 scans (a known way to burn CPU); the CMYK JPEGs that
// OpenImageIO decodes instead were read whatever their count: 20,000 scans took a minute.
TEST(ImageIo, CmykJpegsWithMoreThan500ScansAreRefused) {
  const std::vector<std::uint8_t> jpeg = CmykJpeg(32, 32);  // baseline: one scan
  ASSERT_TRUE(LoadImageBytes(jpeg).image);
  std::size_t scan = jpeg.size();
  for (std::size_t i = 0; i + 1 < jpeg.size(); ++i) {
    if (jpeg[i] == 0xFF && jpeg[i + 1] == 0xDA) scan = i;
  }
  ASSERT_LT(scan, jpeg.size());
  ASSERT_EQ(jpeg[jpeg.size() - 2], 0xFF);
  ASSERT_EQ(jpeg[jpeg.size() - 1], 0xD9);
  std::vector<std::uint8_t> bomb(jpeg.begin(), jpeg.end() - 2);
  for (int copy = 0; copy < 600; ++copy) {
    bomb.insert(bomb.end(), jpeg.begin() + static_cast<std::ptrdiff_t>(scan), jpeg.end() - 2);
  }
  bomb.push_back(0xFF);
  bomb.push_back(0xD9);
  const LoadResult r = LoadImageBytes(bomb);
  EXPECT_FALSE(r.image);
  EXPECT_EQ(r.kind, ImageError::kCorrupt);
  EXPECT_NE(r.error.find("more than 500 scans"), std::string::npos) << r.error;
}

// `pintag detect` reads a file whole: one larger than any photo is refused from its size
// (a sparse file, so the test writes nothing), and a device read up to the limit, not forever.
TEST(ImageIo, AFileLargerThanAnyPhotoIsRefusedUnread) {
  const std::string path = TempPath("huge.jpg");
  { std::ofstream(path, std::ios::binary) << "\xFF\xD8\xFF"; }
  std::filesystem::resize_file(path, (std::uintmax_t{1} << 30) + 1);
  const LoadResult r = LoadImageFile(path);
  EXPECT_FALSE(r.image);
  EXPECT_EQ(r.kind, ImageError::kTooLarge);
  EXPECT_NE(r.error.find("larger than 1 GiB"), std::string::npos) << r.error;
  std::filesystem::remove(path);
}

/// An endless stream of one byte (a device such as /dev/zero), counting what it was asked for.
class EndlessBytes : public std::streambuf {
 public:
  explicit EndlessBytes(char byte) { chunk_.fill(byte); }
  std::size_t given() const { return given_; }

 protected:
  int_type underflow() override {
    setg(chunk_.data(), chunk_.data(), chunk_.data() + chunk_.size());
    given_ += chunk_.size();
    return traits_type::to_int_type(chunk_[0]);
  }

 private:
  std::array<char, 4096> chunk_{};
  std::size_t given_ = 0;
};

// `pintag detect -` reads its photo through LoadImageStream: a photo on a pipe loads like the
// same file, its errors name the stream, and a stream that is no photo is refused from its first
// bytes, not read to the 1 GiB limit.
TEST(ImageIo, APhotoOnAStreamLoadsAndAStreamThatIsNoPhotoIsRefusedAtOnce) {
  const cv::Mat frame = PhoneLikeFrame(96, 64);
  const std::vector<std::uint8_t> png = Encode(".png", frame);
  std::istringstream photo(std::string(png.begin(), png.end()));
  const LoadResult loaded = LoadImageStream(photo, "standard input");
  ASSERT_TRUE(loaded.image) << loaded.error;
  EXPECT_EQ(cv::norm(loaded.image->bgr, frame, cv::NORM_INF), 0.0);

  std::istringstream cut(std::string(png.begin(), png.begin() + static_cast<long>(png.size() / 2)));
  const LoadResult truncated = LoadImageStream(cut, "standard input");
  EXPECT_FALSE(truncated.image);
  EXPECT_EQ(truncated.kind, ImageError::kCorrupt);
  EXPECT_EQ(truncated.error.rfind("standard input: ", 0), 0U) << truncated.error;

  EndlessBytes zeros('\0');
  std::istream endless(&zeros);
  const LoadResult refused = LoadImageStream(endless, "standard input");
  EXPECT_FALSE(refused.image);
  EXPECT_EQ(refused.kind, ImageError::kUnsupported) << refused.error;
  EXPECT_LE(zeros.given(), std::size_t{1} << 20);
}

/// `plain` (a simple WebP) rewrapped as an extended one with an EXIF chunk whose Orientation is
/// `orientation` (a little-endian TIFF block of one entry, as a phone's gallery writes it).
std::vector<std::uint8_t> WebpWithOrientation(const std::vector<std::uint8_t>& plain, int width,
                                              int height, int orientation) {
  std::vector<std::uint8_t> out;
  const auto put = [&](std::initializer_list<std::uint8_t> bytes) {
    out.insert(out.end(), bytes.begin(), bytes.end());
  };
  const auto put32 = [&](std::uint32_t v) {
    put({static_cast<std::uint8_t>(v), static_cast<std::uint8_t>(v >> 8),
         static_cast<std::uint8_t>(v >> 16), static_cast<std::uint8_t>(v >> 24)});
  };
  const auto put24 = [&](std::uint32_t v) {
    put({static_cast<std::uint8_t>(v), static_cast<std::uint8_t>(v >> 8),
         static_cast<std::uint8_t>(v >> 16)});
  };
  put({'R', 'I', 'F', 'F', 0, 0, 0, 0, 'W', 'E', 'B', 'P', 'V', 'P', '8', 'X'});
  put32(10);
  put({0x08, 0, 0, 0});  // flags: EXIF present
  put24(static_cast<std::uint32_t>(width - 1));
  put24(static_cast<std::uint32_t>(height - 1));
  out.insert(out.end(), plain.begin() + 12, plain.end());  // the image chunk as it was
  const std::vector<std::uint8_t> tiff = {
      'I',  'I',  42, 0, 8, 0, 0, 0,  // header, first directory at 8
      1,    0,                        // one entry
      0x12, 0x01, 3,  0, 1, 0, 0, 0, static_cast<std::uint8_t>(orientation),
      0,    0,    0,       // Orientation
      0,    0,    0,  0};  // no next
  put({'E', 'X', 'I', 'F'});
  put32(static_cast<std::uint32_t>(tiff.size()));
  out.insert(out.end(), tiff.begin(), tiff.end());
  const auto riff = static_cast<std::uint32_t>(out.size() - 8);
  for (int i = 0; i < 4; ++i) out[4 + i] = static_cast<std::uint8_t>(riff >> (8 * i));
  return out;
}

// OpenImageIO 2.4 does not read a WebP's EXIF chunk: a phone's rotated WebP was read in its
// stored frame, and a mirrored one found no tag.
TEST(ImageIo, WebpExifOrientationIsApplied) {
  const std::vector<std::uint8_t> plain = ReadAll(Write("plain.webp", 64, 48));
  const LoadResult stored = LoadImageBytes(plain);
  ASSERT_TRUE(stored.image) << stored.error;
  ASSERT_EQ(stored.image->bgr.size(), cv::Size(64, 48));
  for (const int orientation : {1, 2, 6, 8}) {
    const LoadResult r = LoadImageBytes(WebpWithOrientation(plain, 64, 48, orientation));
    ASSERT_TRUE(r.image) << orientation << ": " << r.error;
    EXPECT_EQ(r.image->exif_orientation, orientation);
    cv::Mat expected = stored.image->bgr.clone();  // a new matrix: never written into `stored`
    if (orientation == 2) cv::flip(stored.image->bgr, expected, 1);
    if (orientation == 6) cv::rotate(stored.image->bgr, expected, cv::ROTATE_90_CLOCKWISE);
    if (orientation == 8) cv::rotate(stored.image->bgr, expected, cv::ROTATE_90_COUNTERCLOCKWISE);
    ASSERT_EQ(r.image->bgr.size(), expected.size()) << orientation;
    EXPECT_EQ(cv::norm(r.image->bgr, expected, cv::NORM_INF), 0) << orientation;
  }
}

}  // namespace
}  // namespace pintag
