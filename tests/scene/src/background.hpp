#pragma once
// Scene backgrounds: random crops of installed photographs, or procedural clutter.

#include <opencv2/core.hpp>
#include <string>

#include "pintag/scene/rng.hpp"
#include "pintag/scene/scene.hpp"

namespace pintag::scene::detail {

/// A CV_8UC3 background of the camera's frame size. Uses a photograph when `real` is set and one
/// is installed, else draws one; `name` receives the photo's file name or "procedural".
cv::Mat MakeBackground(const Camera& camera, bool real, Rng& rng, std::string& name);

/// Procedural clutter: gradients, rectangles, disks (red and green among them), lines.
cv::Mat ProceduralBackground(cv::Size size, Rng& rng);

}  // namespace pintag::scene::detail
