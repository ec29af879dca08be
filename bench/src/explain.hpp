#pragma once
// Why PinTag missed a tag, judged against the truth: did any candidate square reach the readers
// near the tag, how far were its corners from the true ones, and do the readers decode the tag on
// its true corners. Runs outside the timed call.

#include <string>

#include "pintag/detector/detector.hpp"
#include "pintag/scene/scene.hpp"

namespace pintag::bench {

/// A short text, starting with 1 (no candidate on the tag), 2 (a candidate, not decoded: its
/// corner error band and rejection) or 3 (decoded there as another key), followed by what the
/// readers make of the tag on its true corners; sorting the texts groups them.
std::string ExplainMiss(const cv::Mat& bgr, ChromaUpsampling upsampling,
                        const scene::MarkerTruth& truth, const scene::Camera& camera,
                        const DetectorOptions& tuned = {});

}  // namespace pintag::bench
