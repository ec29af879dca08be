#pragma once
// Overlapping cluster regions, and quads found with and without gap closing, can reach one tag
// more than once. Of the candidates whose centres lie within a quarter of the square's side of
// each other only one is kept, and a decoded tag always wins over a rejected candidate (those
// are listed only with DetectorOptions::return_rejected, and must never hide a tag).

#include <vector>

#include "pintag/detector/detection.hpp"

namespace pintag::stage {

/// Keeps, in order, the first decoded detection of each place, then the first rejected candidate
/// of each place no decoded one holds. `square_px` of every entry must be set.
void RemoveDuplicates(std::vector<Detection>* detections);

}  // namespace pintag::stage
