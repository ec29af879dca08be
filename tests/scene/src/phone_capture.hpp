#pragma once
// The held-out world's camera: PhoneCapture (scene.hpp) applied to a rendered frame.

#include <opencv2/core.hpp>

#include "pintag/scene/rng.hpp"
#include "pintag/scene/scene.hpp"

namespace pintag::scene::detail {

/// Turns `frame` (CV_8UC3 sRGB, the light arriving at the lens) into what a phone saves and a
/// viewer decodes: see PhoneCapture for the steps. `rng` draws the sensor noise.
void ApplyPhoneCapture(cv::Mat& frame, const PhoneCapture& capture, Rng& rng);

}  // namespace pintag::scene::detail
