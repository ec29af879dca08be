#pragma once
// Scene backgrounds: random crops of installed photographs, or procedural clutter.

#include <opencv2/core.hpp>
#include <string>

#include "pintag/scene/rng.hpp"
#include "pintag/scene/scene.hpp"

namespace pintag::scene::detail {

/// A CV_8UC3 background of the camera's frame size. With `real`, the photographs of `world`
/// (`photo` ≥ 0: that one, else chosen by `rng`, alone or as a 2 × 2 or 3 × 3 collage of crops;
/// throws when one is not installed), else procedural clutter; `name` receives the file names or
/// "procedural".
cv::Mat MakeBackground(const Camera& camera, World world, bool real, int photo, Rng& rng,
                       std::string& name);

/// Procedural clutter: gradients, rectangles, disks (red and green among them), lines.
cv::Mat ProceduralBackground(cv::Size size, Rng& rng);

}  // namespace pintag::scene::detail
