#include "candidates/cluster_quads.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>

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

// A cluster spread over a red-rich photograph can span the whole frame; thresholding and tracing
// such a region cost 3 ms a search. When every blob of the cluster is large, so is any tag that
// holds three of them (an element's red core of 8 px belongs to a square of 40 px or more, one
// of 32 px to 160 px or more), and the region is searched at a half or a quarter of the
// resolution: the tag's square stays 20 px or more there, and its quads are refined at full
// resolution afterwards (step 4) as always.
constexpr int kReducedRegionPx = 250'000;
constexpr double kHalfResolutionMinBlobMajorPx = 8;
constexpr double kQuarterResolutionMinBlobMajorPx = 32;
// The second search, around the blobs alone, pays only where that is a part of the cluster's
// region: over most of it the threshold sees the same pixels again, and ten blobs or more are
// photograph texture spread as widely. Tuning seeds 22-23: 375 such second searches, 873 ms, no
// tag; the 51 tags the second search found came from at most 6 blobs and 65 % of the region.
constexpr double kMaxSecondSearchShare = 0.8;
constexpr std::size_t kMaxSecondSearchBlobs = 9;

// FindQuads on `dark` (the region at `origin`) made `scale` (2 or 4) times smaller; the quads in
// full-resolution coordinates.
std::vector<Quad> FindQuadsReduced(const cv::Mat& dark, cv::Point origin, double min_square_px,
                                   const std::vector<cv::Point2d>& anchors, bool close_gaps,
                                   int min_anchors, int scale) {
  // Halved step by step: OpenCV's area resize is fast for a factor of 2 and ten times slower for
  // 4 (2.5 against 0.2 ms on a 1774 × 1080 region).
  cv::Mat reduced = dark;
  for (int s = 1; s < scale; s *= 2) {
    cv::resize(reduced, reduced, cv::Size(reduced.cols / 2, reduced.rows / 2), 0, 0,
               cv::INTER_AREA);
  }
  std::vector<cv::Point2d> reduced_anchors;
  reduced_anchors.reserve(anchors.size());
  for (const cv::Point2d& a : anchors) reduced_anchors.push_back((a - cv::Point2d(origin)) / scale);
  std::vector<Quad> quads =
      FindQuads(reduced, {0, 0}, min_square_px / scale, &reduced_anchors, close_gaps, min_anchors);
  // Reduced pixel (x, y) covers full-resolution pixels scale x to scale x + scale - 1.
  const cv::Point2d offset = cv::Point2d(origin) + cv::Point2d(scale - 1, scale - 1) / 2;
  for (Quad& quad : quads) {
    for (cv::Point2d& p : quad) p = scale * p + offset;
  }
  return quads;
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
  double smallest_major = 1e300;
  for (int i : cluster.blobs) {
    const RedBlob& blob = blobs[static_cast<std::size_t>(i)];
    anchors.push_back(blob.centroid);
    smallest_major = std::min(smallest_major, blob.major);
  }
  const int reduction = smallest_major >= kQuarterResolutionMinBlobMajorPx ? 4
                        : smallest_major >= kHalfResolutionMinBlobMajorPx  ? 2
                                                                           : 1;
  const auto holds_elements = [&](const Quad& quad) {
    return AssignElements(HomographyFromQuad(quad), blobs, cluster.blobs, kRoughElementTolerance)
               .found >= cluster.min_elements;
  };
  // The quads of `region` (within the cluster's); a large region is searched at reduced
  // resolution, and then around each quad found there that holds the elements again at full
  // resolution: what goes on to refinement is what a full-resolution search gives (a notch left
  // by a covered element, closed at half resolution, cost a tag in the tests).
  const auto search = [&](const cv::Rect& region, bool close_gaps) {
    const cv::Mat part = dark(region - cluster.roi.tl());
    if (region.area() <= kReducedRegionPx || reduction == 1) {
      return FindQuads(part, region.tl(), min_square_px, &anchors, close_gaps,
                       cluster.min_elements);
    }
    std::vector<Quad> found;
    for (const Quad& rough : FindQuadsReduced(part, region.tl(), min_square_px, anchors, close_gaps,
                                              cluster.min_elements, reduction)) {
      if (!holds_elements(rough)) continue;
      const cv::Rect box = cv::boundingRect(std::vector<cv::Point2f>(rough.begin(), rough.end()));
      const int margin = std::max(box.width, box.height) / 4 + reduction;
      const cv::Rect around =
          (box - cv::Point(margin, margin) + cv::Size(2 * margin, 2 * margin)) & region;
      const std::vector<Quad> exact =
          FindQuads(dark(around - cluster.roi.tl()), around.tl(), min_square_px, &anchors,
                    close_gaps, cluster.min_elements);
      found.insert(found.end(), exact.begin(), exact.end());
    }
    return found;
  };
  std::vector<Quad> quads = search(cluster.roi, /*close_gaps=*/true);
  if (cluster.blobs.size() > kMaxSecondSearchBlobs ||
      std::any_of(quads.begin(), quads.end(), holds_elements)) {
    return quads;
  }
  // Only around the blobs: the tag is there, and the rest of the region is photo.
  const cv::Rect around = AnchorsRegion(anchors, cluster.roi);
  if (around.area() < kMaxSecondSearchShare * cluster.roi.area()) {
    const std::vector<Quad> open = search(around, false);
    quads.insert(quads.end(), open.begin(), open.end());
  }
  return quads;
}

}  // namespace pintag::stage
