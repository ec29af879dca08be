#include "cluster_quads.hpp"

#include <algorithm>

#include "homography.hpp"

namespace pintag::stage {

std::vector<Quad> ClusterQuads(const cv::Mat& dark, const BlobCluster& cluster,
                               const std::vector<RedBlob>& blobs, double min_square_px) {
  std::vector<cv::Point2d> anchors;
  for (int i : cluster.blobs) anchors.push_back(blobs[static_cast<std::size_t>(i)].centroid);
  std::vector<Quad> quads = FindQuads(dark, cluster.roi.tl(), min_square_px, &anchors);
  const auto holds_elements = [&](const Quad& quad) {
    return AssignElements(HomographyFromQuad(quad), blobs, cluster.blobs, kRoughElementTolerance)
               .found >= 3;
  };
  if (std::none_of(quads.begin(), quads.end(), holds_elements)) {
    // Only around the blobs: the tag is there, and the rest of the region is photo.
    const cv::Rect near = AnchorsRegion(anchors, cluster.roi);
    const std::vector<Quad> open = FindQuads(dark(near - cluster.roi.tl()), near.tl(),
                                             min_square_px, &anchors, /*close_gaps=*/false);
    quads.insert(quads.end(), open.begin(), open.end());
  }
  return quads;
}

}  // namespace pintag::stage
