// Stage 5b's blur on motion: tags rendered by the scene generator (tests/scene) with a straight
// smear and a little defocus, nothing else, fitted on their true squares.

#include <gtest/gtest.h>

#include <cmath>
#include <optional>

#include "blur_model.hpp"
#include "homography.hpp"
#include "orientation.hpp"
#include "payload.hpp"
#include "pintag/scene/scene.hpp"

namespace pintag::stage {
namespace {

// A camera that moves during the exposure smears each point evenly along a line. The model's
// elongated blur is such a smear (over a round Gaussian for the defocus), so on a tag blurred that
// way the fit finds the smear's direction and its spread (standard deviation along it). An
// elongated Gaussian in its place put the spread 0.3 px too wide here (1.87 px for 1.56 on a
// 36 px tag): its peaked middle and long tails fit a flat smear only when made wider.
TEST(BlurModelMotion, FitsMotionBlurAsASmearAlongItsDirection) {
  constexpr double kDefocusPx = 0.6, kMotionPx = 5, kSquarePx = 36;
  const double spread = std::sqrt(kDefocusPx * kDefocusPx + kMotionPx * kMotionPx / 12);
  const scene::Camera camera;
  int cases = 0;
  for (const double angle : {30.0, 120.0}) {
    for (const int key : {4660, 21845}) {
      scene::SceneSpec spec;
      spec.camera = camera;
      spec.seed = static_cast<std::uint64_t>(key);
      spec.real_background = false;
      spec.photometry.defocus_sigma_px = kDefocusPx;
      spec.photometry.motion_px = kMotionPx;
      spec.photometry.motion_angle_deg = angle;
      scene::PlacedMarker marker;
      marker.id = key;
      marker.texture = scene::PinTagTexture(key, 256);
      marker.pose = scene::MakePose(camera, {900, 500},
                                    scene::DistanceForSquarePx(camera, kSquarePx), 25, 70, 10);
      spec.markers.push_back(marker);
      const scene::Scene rendered = scene::RenderScene(spec);
      ASSERT_EQ(rendered.truth.size(), 1U);

      const BlurFit fit = FitCellsThroughBlur(rendered.bgr, rendered.truth[0].homography);
      ASSERT_TRUE(fit.ok);
      ++cases;
      const double off_axis = std::abs(std::remainder(fit.angle_deg - angle, 180.0));
      EXPECT_LE(off_axis, 23) << "smear at " << angle << "°, fit at " << fit.angle_deg << "°";
      EXPECT_NEAR(fit.sigma_major_px, spread, 0.2) << "smear at " << angle << "°";
      EXPECT_LT(fit.sigma_minor_px, 1.0) << "smear at " << angle << "°";
      const OrientationResult orientation = ReadOrientation(fit.cells, BitThresholds{});
      ASSERT_TRUE(orientation.ok) << orientation.error;
      const PayloadResult payload = DecodePayload(orientation.reading);
      ASSERT_TRUE(payload.key.has_value()) << payload.error;
      EXPECT_EQ(payload.key->value(), key);
    }
  }
  EXPECT_EQ(cases, 4);
}

}  // namespace
}  // namespace pintag::stage
