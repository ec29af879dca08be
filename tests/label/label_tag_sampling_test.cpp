// The tag on a rendered label must read back as the key it was given: sample every cell at its
// nominal centre (codec geometry placed where the label layout says the tag is) and classify the
// colour in CIELAB against the palette.

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>

#include "label_test_util.hpp"
#include "pintag/codec/cells.hpp"
#include "pintag/codec/cielab.hpp"
#include "pintag/codec/geometry.hpp"
#include "pintag/codec/label.hpp"
#include "pintag/codec/palette.hpp"

namespace pintag {
namespace {

// Nearest palette colour by CIE76 ΔE, and how far it is.
std::pair<PaletteColour, double> Classify(Rgb8 pixel) {
  const Lab lab = SrgbToLab(pixel);
  PaletteColour best = PaletteColour::kWhite;
  double best_distance = std::numeric_limits<double>::infinity();
  for (const PaletteEntry& entry : kPalette) {
    const double d = DeltaE76(lab, SrgbToLab(entry.srgb));
    if (d < best_distance) {
      best = entry.colour;
      best_distance = d;
    }
  }
  return {best, best_distance};
}

// Square placement in pixels (fractional allowed) of the tag in some image.
struct Frame {
  double x;
  double y;
  double side;
  Rgb8 at(const RgbImage& image, geometry::Point p) const {
    return image.at(static_cast<int>(std::floor(x + p.x * side)),
                    static_cast<int>(std::floor(y + p.y * side)));
  }
};

// Checks every cell, the square and the quiet zone; `max_delta_e` bounds how far a sample may be
// from its palette colour (tight for our own raster, looser for poppler's).
void ExpectTagReads(const RgbImage& image, const Frame& frame, TagKey key, double max_delta_e) {
  const TagCells cells = EncodeCells(key);
  for (int e = 0; e < kElements; ++e) {
    for (int s = 0; s < kGreenSectors; ++s) {
      const auto [colour, distance] = Classify(frame.at(image, geometry::GreenSectorCentre(e, s)));
      const PaletteColour want =
          cells.green[e][s] ? PaletteColour::kGreenOne : PaletteColour::kGreenZero;
      EXPECT_EQ(colour, want) << "key " << key.value() << " green C" << e << " sector " << s;
      EXPECT_LE(distance, max_delta_e) << "key " << key.value() << " green C" << e << "/" << s;
    }
    for (int q = 0; q < kRedQuadrants; ++q) {
      const auto [colour, distance] = Classify(frame.at(image, geometry::RedQuadrantCentre(e, q)));
      const PaletteColour want = cells.red[e][q] ? PaletteColour::kRedOne : PaletteColour::kRedZero;
      EXPECT_EQ(colour, want) << "key " << key.value() << " red C" << e << " quadrant " << q;
      EXPECT_LE(distance, max_delta_e) << "key " << key.value() << " red C" << e << "/" << q;
    }
  }
  // Black between the elements and at the centre.
  for (geometry::Point p : {geometry::Point{0.5, 0.5}, {0.5, 0.05}, {0.05, 0.5}, {0.95, 0.95}}) {
    EXPECT_EQ(Classify(frame.at(image, p)).first, PaletteColour::kBlack) << p.x << "," << p.y;
  }
}

// Every pixel of the quiet zone band (0.15 of the side, minus a pixel for anti-aliasing at the
// square's edge) is white: no text or rule intrudes.
void ExpectQuietZoneWhite(const RgbImage& image, const LabelTagPixels& tag) {
  const int band = static_cast<int>(std::floor(0.15 * tag.square_side));
  int dirty = 0;
  for (int y = tag.square_y - band; y < tag.square_y + tag.square_side + band; ++y) {
    for (int x = tag.square_x - band; x < tag.square_x + tag.square_side + band; ++x) {
      const bool inside = x >= tag.square_x - 1 && x <= tag.square_x + tag.square_side &&
                          y >= tag.square_y - 1 && y <= tag.square_y + tag.square_side;
      if (inside) continue;
      const Rgb8 c = image.at(x, y);
      if (c.r < 250 || c.g < 250 || c.b < 250) ++dirty;
    }
  }
  EXPECT_EQ(dirty, 0);
}

TEST(LabelTag, PngTagDecodesBackToItsKey) {
  struct Case {
    LabelSize size;
    double dpi = 0;
  };
  const std::array<std::uint16_t, 6> keys = {0, 1, 12345, 21845, 27306, 32767};
  for (const Case& c :
       {Case{kLabel100x150, 300}, Case{kLabelA6, 150}, Case{kLabel4x6In, 203},
        Case{LabelSize{150, 100}, 96}, Case{LabelSize{75, 75}, 72}, Case{LabelSize{50, 75}, 72}}) {
    for (std::uint16_t k : keys) {
      const LabelOptions options{c.size, c.dpi};
      const RenderedLabel png = RenderLabelPng(test::SampleLabel(110001, k), options);
      ASSERT_TRUE(png) << png.error;
      const auto decoded = test::ReadPng(png.bytes);
      ASSERT_TRUE(decoded.has_value());
      const LabelTagPixels tag = TagPlacementPixels(options);
      // The pixel placement agrees with the millimetre one to within a pixel.
      const LabelTagPlacement mm = TagPlacement(c.size);
      const double px_per_mm = c.dpi / 25.4;
      EXPECT_NEAR(tag.square_x, mm.square_x_mm * px_per_mm, 0.5 + 1e-9);
      EXPECT_NEAR(tag.square_side, mm.square_side_mm * px_per_mm, 0.5 + 1e-9);
      SCOPED_TRACE(ToString(c.size) + " @ " + std::to_string(c.dpi) + " dpi");
      ExpectTagReads(decoded->image,
                     {double(tag.square_x), double(tag.square_y), double(tag.square_side)},
                     TagKey(k), 3.0);
      ExpectQuietZoneWhite(decoded->image, tag);
    }
  }
}

TEST(LabelTag, PdfTagDecodesBackToItsKeyThroughPoppler) {
  if (!test::HavePoppler()) GTEST_SKIP() << "poppler-utils not installed";
  test::TempDir dir;
  for (const LabelSize& size : {kLabel100x150, LabelSize{150, 100}}) {
    for (std::uint16_t k : {std::uint16_t{12345}, std::uint16_t{27306}}) {
      const RenderedLabel pdf = RenderLabelPdf(test::SampleLabel(110001, k), {size, 300});
      ASSERT_TRUE(pdf) << pdf.error;
      const auto path = dir.path() / "label.pdf";
      test::WriteFile(path, pdf.bytes);
      constexpr double kDpi = 150;
      ASSERT_TRUE(test::Run("pdftoppm -png -r 150 -singlefile '" + path.string() + "' '" +
                            (dir.path() / "page").string() + "'"));
      std::ifstream in(dir.path() / "page.png", std::ios::binary);
      const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), {});
      const auto decoded = test::ReadPng(bytes);
      ASSERT_TRUE(decoded.has_value());
      const LabelTagPlacement p = TagPlacement(size);
      const double s = kDpi / 25.4;
      SCOPED_TRACE(ToString(size) + " key " + std::to_string(k));
      // poppler renders the PDF's sRGB values unmanaged: the samples are the palette's own.
      ExpectTagReads(decoded->image, {p.square_x_mm * s, p.square_y_mm * s, p.square_side_mm * s},
                     TagKey(k), 3.0);
    }
  }
}

}  // namespace
}  // namespace pintag
