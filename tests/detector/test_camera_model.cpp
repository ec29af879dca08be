// Intrinsics: given, else EXIF, else the assumed field of view.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "pose/camera_model.hpp"

namespace pintag::stage {
namespace {

TEST(CameraModel, GivenWins) {
  DetectorOptions o;
  o.intrinsics = CameraIntrinsics{1500, 1510, 950, 530, {0.1, 0, 0, 0}};
  ExifCamera exif;
  exif.focal_length_35mm = 28;
  const ResolvedCamera c = ResolveCamera(o, &exif, 1920, 1080);
  EXPECT_EQ(c.source, IntrinsicsSource::kGiven);
  EXPECT_EQ(c.intrinsics.fy, 1510);
  EXPECT_EQ(c.intrinsics.distortion.size(), 4u);
}

TEST(CameraModel, Exif35mmEquivalent) {
  ExifCamera exif;
  exif.focal_length_35mm = 26;
  const ResolvedCamera c = ResolveCamera({}, &exif, 4000, 3000);
  EXPECT_EQ(c.source, IntrinsicsSource::kExif);
  EXPECT_NEAR(c.intrinsics.fx, 26 * 5000 / std::hypot(36.0, 24.0), 1e-6);
  EXPECT_NEAR(c.intrinsics.cx, 1999.5, 1e-9);
}

TEST(CameraModel, ExifFocalLengthWithFocalPlaneResolution) {
  ExifCamera exif;
  exif.focal_length_mm = 4.2;
  exif.focal_plane_x_resolution = 2540;  // px per inch = 100 px per mm
  exif.focal_plane_resolution_unit = 2;
  const ResolvedCamera c = ResolveCamera({}, &exif, 4000, 3000);
  EXPECT_EQ(c.source, IntrinsicsSource::kExif);
  EXPECT_NEAR(c.intrinsics.fx, 420, 1e-6);
  exif.focal_plane_resolution_unit = 4;  // per mm
  exif.focal_plane_x_resolution = 250;
  EXPECT_NEAR(ResolveCamera({}, &exif, 4000, 3000).intrinsics.fx, 1050, 1e-6);
}

TEST(CameraModel, FocalLengthsNoLensHasAreTakenAsAbsent) {
  // 65535 is what some EXIF writers put for "unknown": taken at its word it put a tag 273 m away.
  for (const double mm : {65535.0, 5000.0, 1.0}) {
    ExifCamera exif;
    exif.focal_length_35mm = mm;
    EXPECT_EQ(ResolveCamera({}, &exif, 4000, 3000).source, IntrinsicsSource::kAssumed) << mm;
  }
  ExifCamera exif;
  exif.focal_length_mm = 4000;  // with 100 px per mm: about 3,500 mm equivalent on this sensor
  exif.focal_plane_x_resolution = 2540;
  exif.focal_plane_resolution_unit = 2;
  EXPECT_EQ(ResolveCamera({}, &exif, 4000, 3000).source, IntrinsicsSource::kAssumed);
  for (const double mm : {13.0, 26.0, 120.0, 600.0}) {  // phones' ultra-wide to long lenses
    exif = {};
    exif.focal_length_35mm = mm;
    EXPECT_EQ(ResolveCamera({}, &exif, 4000, 3000).source, IntrinsicsSource::kExif) << mm;
  }
}

TEST(CameraModel, AssumedFieldOfViewOtherwise) {
  ExifCamera empty;
  for (const ExifCamera* exif :
       {static_cast<const ExifCamera*>(nullptr), static_cast<const ExifCamera*>(&empty)}) {
    const ResolvedCamera c = ResolveCamera({}, exif, 1920, 1080);
    EXPECT_EQ(c.source, IntrinsicsSource::kAssumed);
    EXPECT_NEAR(2 * std::atan(960 / c.intrinsics.fx) * 180 / std::numbers::pi, 65, 1e-9);
  }
  // A phone held upright: the same lens, so the same focal length, and the same distance to a tag.
  // The field of view is across the longer side, as a phone's is stated.
  const ResolvedCamera portrait = ResolveCamera({}, nullptr, 1080, 1920);
  EXPECT_EQ(portrait.intrinsics.fx, ResolveCamera({}, nullptr, 1920, 1080).intrinsics.fx);
  EXPECT_EQ(portrait.intrinsics.cx, (1080 - 1) / 2.0);
  EXPECT_EQ(portrait.intrinsics.cy, (1920 - 1) / 2.0);
}

}  // namespace
}  // namespace pintag::stage
