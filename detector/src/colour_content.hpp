#pragma once
// Whether a photo holds colour at all. PinTag's bits are red and green: a photo without colour (a
// camera's black-and-white mode, a greyscale scan) can hold no readable tag, and the person
// holding the camera should be told so rather than left to try again in the same mode.

#include <opencv2/core.hpp>

namespace pintag::stage {

/// True when at least 1 in 10,000 of a sample of the pixels (every second pixel of every second
/// row; and at least 16 of them) has channels spread by 8 levels or more. A greyscale image saved
/// as colour has none, whatever its JPEG quality: its chroma planes are flat.
bool HoldsColour(const cv::Mat& bgr);

}  // namespace pintag::stage
