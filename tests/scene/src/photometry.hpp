#pragma once
// Camera degradations applied to a composed frame: light, optics, sensor, codec.

#include <opencv2/core.hpp>

#include "pintag/scene/rng.hpp"
#include "pintag/scene/scene.hpp"

namespace pintag::scene::detail {

/// In place, in this order: exposure, lighting gradient and colour cast, defocus (Gaussian) and
/// motion blur (a line kernel), all in linear light (float); then the sRGB tone curve, Gaussian
/// sensor noise in 8-bit code values, the colour filter array and demosaicing, the phone's
/// processing (tone, saturation, colour denoising, sharpening) and the JPEG round trip.
void ApplyPhotometry(cv::Mat& frame_bgr, const Photometry& photometry, Rng& rng);

}  // namespace pintag::scene::detail
