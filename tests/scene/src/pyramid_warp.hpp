#pragma once
// The held-out world's way of drawing a marker into a frame, deliberately unlike the tuning world's
// supersampled linear-light compositor (composite.hpp): a naive image pipeline's pyramid and
// bilinear warp in sRGB code values, after the printer has had its say on the colours.

#include <cstdint>
#include <opencv2/core.hpp>

#include "pintag/scene/scene.hpp"

namespace pintag::scene::detail {

/// The print's departure from the file: a colour mix near the identity, a paper white that is not
/// quite white, and ink black lifted a little. Applied in linear light.
struct PrintErrors {
  cv::Matx33d mix = cv::Matx33d::eye();  ///< linear BGR → BGR
  cv::Vec3d paper{1, 1, 1};              ///< per channel, linear light
  double black_lift = 0;                 ///< linear light added under the ink, 0 … 0.04
  /// Random errors for one print: mix within a few per cent, paper 0.92 … 1, lift 0.005 … 0.03.
  static PrintErrors Random(std::uint64_t seed);
};

/// Prints `texture`, reduces it by area averaging (cv::INTER_AREA) to the power-of-two level at
/// which one texel is nearest one frame pixel at the marker's centre (geometric mean of the two
/// directions), warps that level bilinearly through `image_from_texture` (texture pixels → frame
/// pixels, pixel centres at integers) and blends it over the frame by its warped coverage, all in
/// 8-bit sRGB. Returns false (drawing nothing) when part of the texture lies behind the camera.
bool WarpThroughPyramid(cv::Mat& frame_bgr, const MarkerTexture& texture,
                        const cv::Matx33d& image_from_texture, const PrintErrors& print);

}  // namespace pintag::scene::detail
