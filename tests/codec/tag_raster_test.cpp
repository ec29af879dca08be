// The raster renderer read back the way a camera would: colours classified in CIELAB at every
// cell's nominal centre, and the black square's edges where the geometry puts them.

#include "pintag/codec/tag_raster.hpp"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <tuple>

#include "pintag/codec/cells.hpp"
#include "pintag/codec/cielab.hpp"
#include "pintag/codec/geometry.hpp"
#include "pintag/codec/palette.hpp"
#include "pintag/codec/png_io.hpp"

namespace pintag {
namespace {

enum class ColourClass { kRedOne, kRedZero, kGreenOne, kGreenZero, kBlack, kWhite, kOther };

ColourClass Classify(Rgb8 colour) {
  const Lab lab = SrgbToLab(colour);
  if (lab.a > 40) return lab.b > 30 ? ColourClass::kRedOne : ColourClass::kRedZero;
  if (lab.a < -15) return lab.b > 30 ? ColourClass::kGreenOne : ColourClass::kGreenZero;
  if (lab.l < 20) return ColourClass::kBlack;
  if (lab.l > 95) return ColourClass::kWhite;
  return ColourClass::kOther;
}

Rgb8 Sample(const TagRaster& raster, geometry::Point p) {
  const double x = raster.square_origin_px + p.x * raster.square_px;
  const double y = raster.square_origin_px + p.y * raster.square_px;
  return raster.image.at(static_cast<int>(std::floor(x)), static_cast<int>(std::floor(y)));
}

class TagRasterCells : public ::testing::TestWithParam<int> {};

TEST_P(TagRasterCells, EveryCellCentreHasTheEncodedColourClass) {
  const int square_px = GetParam();
  for (const int key : {0, 1, 0x2AAA, 0x5555, 1234, 20000, 32767}) {
    const TagRaster raster = RenderTagRaster(TagKey(key), {square_px, 4});
    const TagCells cells = EncodeCells(TagKey(key));
    for (int e = 0; e < kElements; ++e) {
      for (int s = 0; s < kGreenSectors; ++s) {
        const ColourClass expected =
            cells.green[e][s] ? ColourClass::kGreenOne : ColourClass::kGreenZero;
        EXPECT_EQ(Classify(Sample(raster, geometry::GreenSectorCentre(e, s))), expected)
            << "key " << key << " size " << square_px << " C" << e << " sector " << s;
      }
      for (int q = 0; q < kRedQuadrants; ++q) {
        const ColourClass expected = cells.red[e][q] ? ColourClass::kRedOne : ColourClass::kRedZero;
        EXPECT_EQ(Classify(Sample(raster, geometry::RedQuadrantCentre(e, q))), expected)
            << "key " << key << " size " << square_px << " C" << e << " quadrant " << q;
      }
    }
    // Between the elements the square is black, outside it the quiet zone is white.
    EXPECT_EQ(Classify(Sample(raster, {0.5, 0.5})), ColourClass::kBlack);
    EXPECT_EQ(Classify(Sample(raster, {0.5, 0.02})), ColourClass::kBlack);
    EXPECT_EQ(Classify(Sample(raster, {0.5, -0.1})), ColourClass::kWhite);
    EXPECT_EQ(Classify(Sample(raster, {1.1, 0.5})), ColourClass::kWhite);
  }
}

INSTANTIATE_TEST_SUITE_P(Sizes, TagRasterCells, ::testing::Values(64, 65, 83, 128, 301, 512));

// First and last dark pixel along a row or column that crosses the square away from the elements.
std::pair<int, int> DarkRun(const TagRaster& raster, bool horizontal, int line) {
  int first = -1;
  int last = -1;
  for (int i = 0; i < raster.image.width; ++i) {
    const Rgb8 c = horizontal ? raster.image.at(i, line) : raster.image.at(line, i);
    if (SrgbToLab(c).l < 50) {
      if (first < 0) first = i;
      last = i;
    }
  }
  return {first, last};
}

TEST(TagRaster, SquareCornersSitWhereTheGeometrySays) {
  for (const int square_px : {64, 100, 257, 400}) {
    const TagRaster raster = RenderTagRaster(TagKey(321), {square_px, 4});
    const int margin = QuietZonePx(square_px);
    EXPECT_EQ(raster.image.width, square_px + 2 * margin);
    EXPECT_GE(margin, 0.15 * square_px);
    // Rows and columns at 2 % and 98 % of the side pass between the elements' rings.
    for (const double t : {0.02, 0.5, 0.98}) {
      const int line = margin + static_cast<int>(t * square_px);
      for (const bool horizontal : {true, false}) {
        const auto [first, last] = DarkRun(raster, horizontal, line);
        // The square spans continuous [margin, margin + N): first dark pixel index margin, last
        // margin + N − 1, each within a pixel.
        EXPECT_NEAR(first, margin, 1) << square_px << " t=" << t;
        EXPECT_NEAR(last, margin + square_px - 1, 1) << square_px << " t=" << t;
      }
    }
  }
}

// Pixels whose colour is none of the palette's: the blended ones along edges.
int BlendedPixels(const RgbImage& image) {
  int blended = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      const Lab lab = SrgbToLab(image.at(x, y));
      bool pure = false;
      for (const PaletteEntry& entry : kPalette) pure |= DeltaE76(lab, SrgbToLab(entry.srgb)) < 2;
      blended += pure ? 0 : 1;
    }
  }
  return blended;
}

TEST(TagRaster, EdgesAreAntiAliasedOnlyWhenSupersampled) {
  EXPECT_EQ(BlendedPixels(RenderTagRaster(TagKey(4321), {200, 1}).image), 0);
  // Each of the 4 elements has 3 circles and 12 radial edges of ~20 px; expect hundreds.
  EXPECT_GT(BlendedPixels(RenderTagRaster(TagKey(4321), {200, 4}).image), 400);
}

/// Every pixel supersampled, as the renderer once did: the reference its shortcut (pixels inside
/// one cell take that cell's colour unsampled) must match exactly.
RgbImage SupersampleEveryPixel(TagKey key, int n, int ss) {
  const TagCells cells = EncodeCells(key);
  const int margin = QuietZonePx(n);
  RgbImage image(n + 2 * margin, n + 2 * margin);
  for (int py = 0; py < image.height; ++py) {
    for (int px = 0; px < image.width; ++px) {
      double r = 0, g = 0, b = 0;
      for (int sy = 0; sy < ss; ++sy) {
        for (int sx = 0; sx < ss; ++sx) {
          const geometry::CellAt cell = geometry::LocateCell((px - margin + (sx + 0.5) / ss) / n,
                                                             (py - margin + (sy + 0.5) / ss) / n);
          PaletteColour colour = PaletteColour::kWhite;
          if (cell.region == geometry::Region::kBlack) colour = PaletteColour::kBlack;
          if (cell.region == geometry::Region::kRed) {
            colour = cells.red[cell.element][cell.index] ? PaletteColour::kRedOne
                                                         : PaletteColour::kRedZero;
          }
          if (cell.region == geometry::Region::kGreen) {
            colour = cells.green[cell.element][cell.index] ? PaletteColour::kGreenOne
                                                           : PaletteColour::kGreenZero;
          }
          const Rgb8 c = kPalette[static_cast<int>(colour)].srgb;
          r += SrgbToLinear(c.r);
          g += SrgbToLinear(c.g);
          b += SrgbToLinear(c.b);
        }
      }
      const double w = 1.0 / (ss * ss);
      image.set(px, py, {LinearToSrgb(r * w), LinearToSrgb(g * w), LinearToSrgb(b * w)});
    }
  }
  return image;
}

TEST(TagRaster, OnlyBoundaryPixelsNeedSamplingAndTheResultIsExact) {
  for (const auto& [key, n, ss] :
       {std::tuple{1, kMinTagSquarePx, 4}, std::tuple{22222, 65, 4}, std::tuple{4321, 200, 4},
        std::tuple{32767, 512, 4}, std::tuple{99, 301, 2}, std::tuple{7, 128, 1},
        // Sizes drawn before, with other keys: the layout kept for a size serves every key.
        std::tuple{12345, 512, 4}, std::tuple{2, kMinTagSquarePx, 4}}) {
    const RgbImage fast = RenderTagRaster(TagKey(key), {n, ss}).image;
    const RgbImage reference = SupersampleEveryPixel(TagKey(key), n, ss);
    ASSERT_EQ(fast.width, reference.width);
    int differing = 0;
    for (int y = 0; y < fast.height; ++y) {
      for (int x = 0; x < fast.width; ++x) {
        const Rgb8 a = fast.at(x, y);
        const Rgb8 b = reference.at(x, y);
        differing += a.r != b.r || a.g != b.g || a.b != b.b;
      }
    }
    EXPECT_EQ(differing, 0) << "key " << key << ", " << n << " px, supersample " << ss;
  }
}

TEST(PngIo, RecordsTheRequestedDpiInFileAndMemory) {
  const TagRaster raster = RenderTagRaster(TagKey(99), {64, 2});
  const std::string path =
      (std::filesystem::temp_directory_path() / "pintag_dpi_test.png").string();
  std::string error;
  ASSERT_TRUE(WritePng(raster.image, path, 600, &error)) << error;
  auto in = OIIO::ImageInput::open(path);
  ASSERT_TRUE(in);
  // PNG stores whole pixels per metre, so 600 dpi comes back as 23622 / 39.37 = 599.999.
  EXPECT_NEAR(in->spec().get_float_attribute("XResolution"), 600.0, 0.01);
  EXPECT_NEAR(in->spec().get_float_attribute("YResolution"), 600.0, 0.01);
  EXPECT_EQ(in->spec().get_string_attribute("ResolutionUnit"), "inch");
  EXPECT_EQ(in->spec().width, raster.image.width);
  in->close();
  std::filesystem::remove(path);

  std::vector<std::uint8_t> bytes = EncodePng(raster.image, 300, &error);
  ASSERT_FALSE(bytes.empty()) << error;
  OIIO::Filesystem::IOMemReader reader(bytes.data(), bytes.size());
  OIIO::ImageSpec config;
  OIIO::Filesystem::IOProxy* proxy = &reader;
  config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
  auto memory_in = OIIO::ImageInput::open("memory.png", &config);
  ASSERT_TRUE(memory_in);
  EXPECT_NEAR(memory_in->spec().get_float_attribute("XResolution"), 300.0, 0.01);
  std::vector<std::uint8_t> pixels(raster.image.pixels.size());
  ASSERT_TRUE(memory_in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, pixels.data()));
  EXPECT_EQ(pixels, raster.image.pixels);
}

TEST(PngIo, UnwritablePathIsAnErrorValue) {
  std::string error;
  EXPECT_FALSE(WritePng(RgbImage(4, 4), "/nonexistent-dir/x.png", 300, &error));
  EXPECT_FALSE(error.empty());
}

}  // namespace
}  // namespace pintag
