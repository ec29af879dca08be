#pragma once
// Draws a marker texture into a frame through a homography, anti-aliased by supersampling.

#include <opencv2/core.hpp>

#include "pintag/scene/scene.hpp"

namespace pintag::scene::detail {

/// A texture in linear light, BGR plus coverage (1) in the fourth channel.
struct LinearTexture {
  cv::Mat base;  ///< CV_32FC4
};

/// The texture with its occluders drawn on it, converted to linear light.
LinearTexture PrepareTexture(const MarkerTexture& texture, const std::vector<Occluder>& occluders);

/// Inverse-maps a `supersample`× finer grid over the marker's bounding box through
/// `image_from_texture` (texture pixels → frame pixels, pixel centres at integers for both),
/// sampling the texture bilinearly at a mip level whose texels are no larger than a sub-sample,
/// area-averages down to frame pixels and blends with the frame by coverage in linear light.
/// Returns false (drawing nothing) when part of the texture lies behind the camera.
bool CompositeMarker(cv::Mat& frame_bgr, const LinearTexture& texture,
                     const cv::Matx33d& image_from_texture, int supersample);

}  // namespace pintag::scene::detail
