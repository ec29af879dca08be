#pragma once
// Stage 3b for one blob cluster: the quads its tag can be. Quads are searched in the thresholded
// region with gaps of one or two pixels closed; when none of them places 3 of the cluster's blobs
// on its elements (roughly, before corner refinement), again without the closing, around the blobs
// only: tilted steeply, a tag's quiet zone is about two pixels wide across the tilt, the closing
// bridges it, and on dark ground the tag merges with the ground (48 px tags at 72° in the
// benchmark). A region over 250,000 px (a cluster spread over red clutter) is searched at half or
// quarter resolution when all its blobs are large, and again at full resolution only around the
// quads found there that hold the elements. The detector and the benchmark's miss explanation
// both call this. When none of a
// cluster's quads decodes, the detector also tries the quads its blobs place (QuadsFromElements).

#include <vector>

#include "candidates/grouping.hpp"
#include "candidates/quads.hpp"
#include "candidates/red_blobs.hpp"

namespace pintag::stage {

/// Largest cluster (blobs) whose blobs may place quads on their own.
inline constexpr std::size_t kMaxBlobsForElementQuads = 6;

/// The square as element centres place it, clockwise on screen. Centres sit at 0.25 and 0.75 of
/// the side, so the corners are the centres' frame extended by half a spacing each way. Four
/// centres fix a perspective frame (one quad); three fix an affine frame once one of them is
/// taken as the corner element between the other two, so they give three quads, one per choice.
/// Only convex quads are returned (collinear centres, a dart-shaped ring of four or a frame
/// seen beyond its horizon give none). Other counts give none.
std::vector<Quad> QuadsFromElements(const std::vector<cv::Point2d>& centres);

/// The quads a cluster's blobs place: QuadsFromElements of all of them when there are 3 or 4,
/// of every 4 of them when there are 5 or 6 (a stray red blob near the tag), none above
/// kMaxBlobsForElementQuads; each with every corner inside `cluster.roi` and no side shorter
/// than 0.3 `min_square_px` (FindQuads' bound).
std::vector<Quad> ClusterElementQuads(const BlobCluster& cluster, const std::vector<RedBlob>& blobs,
                                      double min_square_px);

/// `dark`: MinChannel of `cluster.roi`. Quads in image coordinates, gaps-closed ones first.
std::vector<Quad> ClusterQuads(const cv::Mat& dark, const BlobCluster& cluster,
                               const std::vector<RedBlob>& blobs, double min_square_px);

}  // namespace pintag::stage
