#pragma once
// Stage 3b, grouping: which red blobs may belong to one tag (clusters, each giving a region of
// interest for the quad search), and which blob sits at which element of a found quad.

#include <array>
#include <opencv2/core.hpp>
#include <vector>

#include "candidates/red_blobs.hpp"

namespace pintag::stage {

struct BlobCluster {
  std::vector<int> blobs;  ///< indices into the blob list
  cv::Rect roi;            ///< where the tag's square and quiet zone can be, clipped to the image
  int min_elements = 3;    ///< blobs a quad must place on elements: 3, or 2 for a pair
};

/// Links blobs whose distance fits elements of one tag (neighbouring elements are 2.5 disk
/// diameters apart) and returns the groups of at least `min_blobs` and (when `max_blobs` > 0) at
/// most `max_blobs` blobs, with their regions.
std::vector<BlobCluster> ClusterBlobs(const std::vector<RedBlob>& blobs, cv::Size image,
                                      int min_blobs = 3, int max_blobs = 0);

struct ElementAssignment {
  std::array<int, 4> blob{-1, -1, -1, -1};  ///< blob index at element slot e, or −1
  int found = 0;
  /// Two blobs at one slot, or a red blob elsewhere inside the square (not a fringe of its edge).
  bool conflict = false;
};

/// A red blob inside the square is taken for a colour fringe of its edge rather than a conflict
/// (AssignElements) when it lies within kFringeBand (tag units) of the edge, outside every
/// element's green ring, and its area is at most kFringeAreaRatio of the smallest element blob's
/// and at most kFringeMaxAreaPx: fringes are a few pixels whatever the tag's size.
inline constexpr double kFringeBand = 0.1;
inline constexpr double kFringeAreaRatio = 0.25;
inline constexpr int kFringeMaxAreaPx = 16;

/// Maps blobs through `tag_to_image` (unit square -> px) and assigns each to the element whose
/// nominal centre it lies near (within `tolerance` tag units in u and in v). A blob inside the
/// square on no element is a conflict, unless it is a colour fringe of the square's edge (see
/// kFringeBand); so are two blobs at one slot, unless both are pieces of its red disk: their
/// centroids lie within the disk's radius of its centre. (Where a disk's bit-0 quadrants are
/// darker than its bit-1 ones, blur and a steep tilt can leave only the lighter ones red enough.)
inline constexpr double kElementTolerance = 0.08;
/// For a quad before corner refinement: a blurred square's thresholded outline can be several
/// pixels off along a steeply tilted side (slots are 0.5 apart, so still unambiguous).
inline constexpr double kRoughElementTolerance = 0.15;
ElementAssignment AssignElements(const cv::Matx33d& tag_to_image, const std::vector<RedBlob>& blobs,
                                 const std::vector<int>& candidates,
                                 double tolerance = kElementTolerance);

}  // namespace pintag::stage
