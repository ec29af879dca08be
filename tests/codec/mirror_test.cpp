// A tag in a mirror: the cells MirrorCells says, read off a rendered tag flipped left to right,
// and the keys whose mirror image is another valid tag.

#include "pintag/codec/mirror.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "pintag/codec/cielab.hpp"
#include "pintag/codec/geometry.hpp"
#include "pintag/codec/tag_raster.hpp"

namespace pintag {
namespace {

// The bit a cell's colour carries: high b* is 1 for both reds and greens.
bool BitOf(Rgb8 colour) {
  return SrgbToLab(colour).b > 30;
}

// The pixel at `p` (square units) of the raster flipped left to right.
Rgb8 SampleMirrored(const TagRaster& raster, geometry::Point p) {
  const double x = raster.square_origin_px + (1.0 - p.x) * raster.square_px;
  const double y = raster.square_origin_px + p.y * raster.square_px;
  return raster.image.at(static_cast<int>(std::floor(x)), static_cast<int>(std::floor(y)));
}

TEST(Mirror, CellsAreWhatAFlippedTagShows) {
  for (const int key : {0, 1, 55, 0x2AAA, 0x5555, 12345, 32767}) {
    const TagRaster raster = RenderTagRaster(TagKey(key), {301, 4});
    const TagCells mirrored = MirrorCells(EncodeCells(TagKey(key)));
    for (int e = 0; e < kElements; ++e) {
      for (int s = 0; s < kGreenSectors; ++s) {
        EXPECT_EQ(BitOf(SampleMirrored(raster, geometry::GreenSectorCentre(e, s))),
                  mirrored.green[e][s])
            << "key " << key << " element " << e << " sector " << s;
      }
      for (int q = 0; q < kRedQuadrants; ++q) {
        EXPECT_EQ(BitOf(SampleMirrored(raster, geometry::RedQuadrantCentre(e, q))),
                  mirrored.red[e][q])
            << "key " << key << " element " << e << " quadrant " << q;
      }
    }
  }
}

TEST(Mirror, OneKeyIn32HasAValidMirrorImageAndMirroringTwiceGivesItBack) {
  int valid = 0;
  for (int k = 0; k < kKeyCount; ++k) {
    const std::optional<TagKey> image = MirrorImageKey(TagKey(k));
    if (!image) continue;
    ++valid;
    const std::optional<TagKey> back = MirrorImageKey(*image);
    ASSERT_TRUE(back.has_value()) << k;
    EXPECT_EQ(back->value(), k);
  }
  // The mirrored payload's copies always agree, and the flip is linear in the cells: the keys
  // whose flipped reading passes the five independent parity checks are a subspace of 2^(15-5).
  EXPECT_EQ(valid, kKeyCount / 32);
}

}  // namespace
}  // namespace pintag
