#pragma once
// A label from a running server, photographed: the label PNG as a marker texture at a known pose
// in a synthetic camera scene, saved as JPEG. For tests that upload real photos to /detect.

#include <gtest/gtest.h>
#include <httplib.h>

#include <string>

#include "pintag/scene/scene.hpp"

namespace pintag::serve_test {

struct Photo {
  std::string jpeg;
  scene::MarkerTruth truth;
  scene::Camera camera;
  double square_mm = 0;
};

/// The label PNG for `pin` (GET /api/v1/labels/{pin}.png, 300 dpi) at a known pose: the square
/// about 220 px across near the centre of `camera`'s frame, tilted `tilt_deg`. Test failures are
/// recorded and an empty JPEG returned when the label cannot be fetched.
Photo PhotographLabel(httplib::Client& client, const httplib::Headers& auth, const std::string& pin,
                      double tilt_deg, const scene::Camera& camera = {});

}  // namespace pintag::serve_test
