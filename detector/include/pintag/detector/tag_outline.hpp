#pragma once
// The one drawing of a found tag on a photo: its square outlined, a dot on C0 (the corner the tag
// is read from) and a caption above it. The HTTP overlay, `pintag detect --overlay` and the
// detector's debug images (--debug-dir) all draw with it, so they look alike.

#include <opencv2/core.hpp>
#include <string>

#include "pintag/detector/detection.hpp"

namespace pintag {

/// Line width in pixels for a photo of this size: 2 px up to 1200 px, thicker beyond, so an
/// outline stays visible when a 12 MP photo is shown scaled down.
int OutlineThickness(const cv::Mat& image);

/// Draws on `image` (BGR, CV_8UC3) in place; `caption` may be empty.
void DrawTagOutline(cv::Mat& image, const Detection& detection, const cv::Scalar& colour,
                    const std::string& caption);

}  // namespace pintag
