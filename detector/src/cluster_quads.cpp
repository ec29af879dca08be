#include "cluster_quads.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "homography.hpp"

namespace pintag::stage {

namespace {

// Every turn the same way (clockwise on screen): a convex quad with no folded or flat corner.
bool IsConvexClockwise(const Quad& q) {
  for (int i = 0; i < 4; ++i) {
    const cv::Point2d a = q[static_cast<std::size_t>(i)];
    const cv::Point2d b = q[static_cast<std::size_t>((i + 1) % 4)];
    const cv::Point2d c = q[static_cast<std::size_t>((i + 2) % 4)];
    if ((b - a).cross(c - b) <= 0) return false;
  }
  return true;
}

}  // namespace

std::vector<Quad> QuadsFromElements(const std::vector<cv::Point2d>& centres) {
  std::vector<Quad> quads;
  const auto keep = [&](const Quad& quad) {
    if (IsConvexClockwise(quad)) quads.push_back(quad);
  };
  if (centres.size() == 3) {
    for (int corner = 0; corner < 3; ++corner) {
      const cv::Point2d a = centres[static_cast<std::size_t>(corner)];
      cv::Point2d u = centres[static_cast<std::size_t>((corner + 1) % 3)] - a;
      cv::Point2d v = centres[static_cast<std::size_t>((corner + 2) % 3)] - a;
      if (u.cross(v) < 0) std::swap(u, v);  // clockwise on screen (y down)
      keep({a - 0.5 * u - 0.5 * v, a + 1.5 * u - 0.5 * v, a + 1.5 * u + 1.5 * v,
            a - 0.5 * u + 1.5 * v});  // collinear centres give a flat quad, refused
    }
  } else if (centres.size() == 4) {
    cv::Point2d mean;
    for (const cv::Point2d& c : centres) mean += c / 4;
    std::vector<cv::Point2d> ring = centres;
    std::sort(ring.begin(), ring.end(), [&](cv::Point2d p, cv::Point2d q) {
      return std::atan2(p.y - mean.y, p.x - mean.x) < std::atan2(q.y - mean.y, q.x - mean.x);
    });
    Quad elements;
    std::copy(ring.begin(), ring.end(), elements.begin());
    // A dart-shaped ring would put the perspective's horizon inside the square.
    if (!IsConvexClockwise(elements)) return quads;
    const cv::Matx33d h = HomographyFromQuad(elements);  // unit square -> element centres
    Quad quad;
    // Element centres are the unit square scaled by 0.5 about its centre: corners at −0.5, 1.5.
    const std::array<cv::Point2d, 4> corners = {
        {{-0.5, -0.5}, {1.5, -0.5}, {1.5, 1.5}, {-0.5, 1.5}}};
    for (std::size_t i = 0; i < 4; ++i) {
      const cv::Vec3d p = h * cv::Vec3d(corners[i].x, corners[i].y, 1);
      if (p[2] <= 0) return quads;  // beyond the horizon
      quad[i] = {p[0] / p[2], p[1] / p[2]};
    }
    keep(quad);
  }
  return quads;
}

std::vector<Quad> ClusterElementQuads(const BlobCluster& cluster, const std::vector<RedBlob>& blobs,
                                      double min_square_px) {
  std::vector<cv::Point2d> centres;
  centres.reserve(cluster.blobs.size());
  for (int i : cluster.blobs) centres.push_back(blobs[static_cast<std::size_t>(i)].centroid);
  std::vector<Quad> quads;
  if (centres.size() > kMaxBlobsForElementQuads) return quads;
  // As FindQuads keeps them: no side shorter than 0.3 min_square_px, and (here) every corner in
  // the cluster's region, where the square and its quiet zone can be.
  const cv::Rect2d region(cluster.roi);
  const auto plausible = [&](const Quad& q) {
    for (std::size_t i = 0; i < 4; ++i) {
      if (!region.contains(q[i])) return false;
      if (cv::norm(q[(i + 1) % 4] - q[i]) < 0.3 * min_square_px) return false;
    }
    return true;
  };
  if (centres.size() <= 4) {
    for (const Quad& q : QuadsFromElements(centres)) {
      if (plausible(q)) quads.push_back(q);
    }
    return quads;
  }
  const std::size_t n = centres.size();
  for (std::size_t a = 0; a < n; ++a) {
    for (std::size_t b = a + 1; b < n; ++b) {
      for (std::size_t c = b + 1; c < n; ++c) {
        for (std::size_t d = c + 1; d < n; ++d) {
          for (const Quad& q :
               QuadsFromElements({centres[a], centres[b], centres[c], centres[d]})) {
            if (plausible(q)) quads.push_back(q);
          }
        }
      }
    }
  }
  return quads;
}

std::vector<Quad> ClusterQuads(const cv::Mat& dark, const BlobCluster& cluster,
                               const std::vector<RedBlob>& blobs, double min_square_px) {
  std::vector<cv::Point2d> anchors;
  for (int i : cluster.blobs) anchors.push_back(blobs[static_cast<std::size_t>(i)].centroid);
  std::vector<Quad> quads = FindQuads(dark, cluster.roi.tl(), min_square_px, &anchors,
                                      /*close_gaps=*/true, cluster.min_elements);
  const auto holds_elements = [&](const Quad& quad) {
    return AssignElements(HomographyFromQuad(quad), blobs, cluster.blobs, kRoughElementTolerance)
               .found >= cluster.min_elements;
  };
  if (std::none_of(quads.begin(), quads.end(), holds_elements)) {
    // Only around the blobs: the tag is there, and the rest of the region is photo.
    const cv::Rect near = AnchorsRegion(anchors, cluster.roi);
    const std::vector<Quad> open =
        FindQuads(dark(near - cluster.roi.tl()), near.tl(), min_square_px, &anchors,
                  /*close_gaps=*/false, cluster.min_elements);
    quads.insert(quads.end(), open.begin(), open.end());
  }
  return quads;
}

}  // namespace pintag::stage
