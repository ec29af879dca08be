#include "candidates/grouping.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

#include "pintag/codec/geometry.hpp"

namespace pintag::stage {
namespace {

// Neighbouring elements are 2.5 disk diameters apart, but a blurred small disk passes the redness
// test only in its core, which can be half the disk or less: links reach 6 core diameters.
constexpr double kLinkDiameters = 6.0;
constexpr double kMaxAreaRatio = 8;    // perspective can shrink a far element
constexpr double kRoiDiameters = 2.6;  // element centre -> square edge + quiet zone: 2.0
constexpr double kRoiSpacings = 1.0;   // the same in element spacings (0.5 S): 0.8
constexpr double kPairRoiSpacings = 1.8;

int Find(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

}  // namespace

std::vector<BlobCluster> ClusterBlobs(const std::vector<RedBlob>& blobs, cv::Size image,
                                      int min_blobs, int max_blobs) {
  const int n = static_cast<int>(blobs.size());
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return blobs[a].centroid.x < blobs[b].centroid.x; });
  double max_major = 0;
  for (const RedBlob& b : blobs) max_major = std::max(max_major, b.major);
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  for (int oi = 0; oi < n; ++oi) {
    const RedBlob& a = blobs[order[oi]];
    for (int oj = oi + 1; oj < n; ++oj) {
      const RedBlob& b = blobs[order[oj]];
      if (b.centroid.x - a.centroid.x > kLinkDiameters * max_major) break;
      const double reach = kLinkDiameters * std::max(a.major, b.major);
      const cv::Point2d d = b.centroid - a.centroid;
      if (d.dot(d) > reach * reach) continue;
      const double ratio = static_cast<double>(std::max(a.area, b.area)) / std::min(a.area, b.area);
      if (ratio > kMaxAreaRatio) continue;
      parent[Find(parent, order[oi])] = Find(parent, order[oj]);
    }
  }
  std::vector<std::vector<int>> groups(n);
  for (int i = 0; i < n; ++i) groups[Find(parent, i)].push_back(i);

  std::vector<BlobCluster> clusters;
  const cv::Rect frame(0, 0, image.width, image.height);
  for (auto& group : groups) {
    const int size = static_cast<int>(group.size());
    // Before the region: its nearest-neighbour passes take the square of the group's size.
    if (size < min_blobs || (max_blobs > 0 && size > max_blobs)) continue;
    double x0 = 1e18, y0 = 1e18, x1 = -1e18, y1 = -1e18, major = 0;
    const auto include = [&](cv::Point2d p) {
      x0 = std::min(x0, p.x), y0 = std::min(y0, p.y), x1 = std::max(x1, p.x),
      y1 = std::max(y1, p.y);
    };
    for (int i : group) {
      include(blobs[i].centroid);
      major = std::max(major, blobs[i].major);
    }
    // One element may be missing: add the fourth corner of the parallelogram that each blob
    // makes with two of its nearest neighbours (the hidden element is opposite the element
    // adjacent to both others).
    for (int i : group) {
      std::array<std::pair<double, int>, 4> nearest;
      nearest.fill({1e300, -1});
      for (int j : group) {
        if (j == i) continue;
        const cv::Point2d d = blobs[j].centroid - blobs[i].centroid;
        std::pair<double, int> candidate{d.dot(d), j};
        for (auto& slot : nearest) {
          if (candidate.first < slot.first) std::swap(candidate, slot);
        }
      }
      for (std::size_t a = 0; a < nearest.size(); ++a) {
        for (std::size_t b = a + 1; b < nearest.size(); ++b) {
          if (nearest[a].second < 0 || nearest[b].second < 0) continue;
          include(blobs[nearest[a].second].centroid + blobs[nearest[b].second].centroid -
                  blobs[i].centroid);
        }
      }
    }
    // Blob sizes understate a blurred tag; the spacing of its elements does not.
    double spacing = 0;
    for (int i : group) {
      double nearest = 1e300;
      for (int j : group) {
        if (j != i) nearest = std::min(nearest, cv::norm(blobs[j].centroid - blobs[i].centroid));
      }
      spacing = std::max(spacing, nearest);
    }
    // A pair may be two neighbours: the far side of the square and its quiet zone are then
    // 0.75 + 0.15 sides, 1.8 spacings, away.
    const bool pair = group.size() == 2;
    const double m =
        std::max(kRoiDiameters * major, (pair ? kPairRoiSpacings : kRoiSpacings) * spacing);
    const cv::Rect roi(cv::Point(static_cast<int>(x0 - m), static_cast<int>(y0 - m)),
                       cv::Point(static_cast<int>(x1 + m) + 1, static_cast<int>(y1 + m) + 1));
    const int min_elements = std::min(3, static_cast<int>(group.size()));
    BlobCluster cluster{std::move(group), roi & frame, min_elements};
    if (cluster.roi.area() > 0) clusters.push_back(std::move(cluster));
  }
  return clusters;
}

ElementAssignment AssignElements(const cv::Matx33d& tag_to_image, const std::vector<RedBlob>& blobs,
                                 const std::vector<int>& candidates, double tolerance) {
  ElementAssignment result;
  const cv::Matx33d inverse = tag_to_image.inv();
  // Blobs inside the square but on no element: a conflict unless they are fringes (below).
  std::vector<std::pair<int, cv::Point2d>> elsewhere;
  std::array<cv::Point2d, 4> slot_uv;  // where each slot's blob lies, tag units
  for (int i : candidates) {
    const cv::Vec3d p = inverse * cv::Vec3d(blobs[i].centroid.x, blobs[i].centroid.y, 1);
    if (std::abs(p[2]) < 1e-12) continue;
    const double u = p[0] / p[2], v = p[1] / p[2];
    if (u < 0 || u > 1 || v < 0 || v > 1) continue;
    bool placed = false;
    for (int e = 0; e < 4; ++e) {
      const geometry::Point c = geometry::kElementCentres[e];
      if (std::abs(u - c.x) > tolerance || std::abs(v - c.y) > tolerance) continue;
      placed = true;
      if (result.blob[e] < 0) {
        result.blob[e] = i;
        slot_uv[e] = {u, v};
        ++result.found;
        continue;
      }
      // A second blob at a slot is another piece of the element's red disk when both centroids
      // lie inside it; otherwise it is red where the format has none.
      const auto inside_disk = [&](cv::Point2d at) {
        return std::hypot(at.x - c.x, at.y - c.y) <= geometry::kRedRadius;
      };
      if (!inside_disk({u, v}) || !inside_disk(slot_uv[e])) {
        result.conflict = true;
      } else if (blobs[static_cast<std::size_t>(i)].area >
                 blobs[static_cast<std::size_t>(result.blob[e])].area) {
        result.blob[e] = i;  // the slot names its largest piece
        slot_uv[e] = {u, v};
      }
    }
    if (!placed) elsewhere.emplace_back(i, cv::Point2d(u, v));
  }
  // Red where the format has none refuses the square, except a fringe (grouping.hpp,
  // kFringeBand): demosaicing and lateral colour put specks of false red along the square's
  // black-to-white edge, often several; on tags of 60-80 px at 65-72 deg they were the only reason
  // tags read at their true corners were refused.
  int least_element_area = 0;
  for (const int b : result.blob) {
    if (b < 0) continue;
    const int area = blobs[static_cast<std::size_t>(b)].area;
    least_element_area = least_element_area == 0 ? area : std::min(least_element_area, area);
  }
  for (const auto& [i, uv] : elsewhere) {
    const bool on_black = geometry::LocateCell(uv.x, uv.y).region == geometry::Region::kBlack;
    const double to_edge = std::min({uv.x, 1 - uv.x, uv.y, 1 - uv.y});
    const int area = blobs[static_cast<std::size_t>(i)].area;
    const bool fringe = on_black && to_edge <= kFringeBand && area <= kFringeMaxAreaPx &&
                        area <= kFringeAreaRatio * least_element_area;
    if (!fringe) result.conflict = true;
  }
  return result;
}

}  // namespace pintag::stage
