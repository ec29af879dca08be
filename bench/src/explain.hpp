#pragma once
// Why PinTag missed a tag: the first stage of the pipeline that lost it, judged against the truth.
// Runs outside the timed call (only with --explain-misses); uses the stage functions of
// detector/src for the first two stages and the detector's own rejected candidates for the rest.

#include <string>
#include <vector>

#include "pintag/detector/detector.hpp"
#include "pintag/scene/scene.hpp"

namespace pintag::bench {

/// Why a PinTag detector with `tuned` options (intrinsics of `camera` and the sweep's tag size
/// set here) does not report `truth` in `bgr`: a short text starting with the number of the stage
/// that lost the tag (1 red pixels, 2 blobs, 3a ring check, 3b grouping, 3c quad search, 3d element
/// match of the rough quad, 4 edges and element match, 5 orientation, 6 payload and parity, 7 none
/// of these, 8 decoded elsewhere), so that sorting the texts sorts them in pipeline order. Stages 1
/// to 3 are re-run here as detector.cpp runs them (keep them in step with it).
std::string ExplainMiss(const cv::Mat& bgr, const scene::MarkerTruth& truth,
                        const scene::Camera& camera, const DetectorOptions& tuned = {});

}  // namespace pintag::bench
