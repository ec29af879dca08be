#include "reading/region_coverage.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <span>

#include "pintag/codec/geometry.hpp"

namespace pintag::reading {
namespace {

constexpr int kSubsamples = 4;  // per pixel side, for a pixel holding several regions

struct PixelCorner {
  double u = 0, v = 0;
  int region = kQuietRegion;
  bool front = false;
};

// The one region holding the whole pixel with these corners, or −1 when it may hold more (its
// sub-samples decide then). With every corner in front of the camera the pixel maps onto the
// convex hull of its corners, so: beyond one side of the square (a half-plane) when all four are;
// inside a red quadrant (convex) when all four are; inside a green sector or the black when all
// four are and a circle around the corners keeps clear of the disks cut out of that region.
int WholeRegion(const std::array<const PixelCorner*, 4>& corners) {
  constexpr double kMargin = 1e-6;
  std::array<bool, 4> beyond{true, true, true, true};  // u < 0, u > 1, v < 0, v > 1
  double mean_u = 0, mean_v = 0;
  for (const PixelCorner* c : corners) {
    if (!c->front) return -1;
    beyond[0] = beyond[0] && c->u < -kMargin;
    beyond[1] = beyond[1] && c->u > 1 + kMargin;
    beyond[2] = beyond[2] && c->v < -kMargin;
    beyond[3] = beyond[3] && c->v > 1 + kMargin;
    mean_u += c->u / 4, mean_v += c->v / 4;
  }
  if (beyond[0] || beyond[1] || beyond[2] || beyond[3]) return kQuietRegion;
  const int region = corners[0]->region;
  if (region == kQuietRegion) return -1;
  for (std::size_t k = 1; k < corners.size(); ++k) {
    if (corners[k]->region != region) return -1;
  }
  const bool red_quadrant =
      region != kBlackRegion && (region - 2) % kCellsPerElement < kRedQuadrants;
  if (red_quadrant) return region;
  double reach2 = 0;
  for (const PixelCorner* c : corners) {
    reach2 =
        std::max(reach2, (c->u - mean_u) * (c->u - mean_u) + (c->v - mean_v) * (c->v - mean_v));
  }
  const auto clear_of = [&](int element, double radius) {
    const geometry::Point centre = geometry::kElementCentres[element];
    const double du = mean_u - centre.x, dv = mean_v - centre.y;
    const double gap = radius + std::sqrt(reach2) + kMargin;
    return du * du + dv * dv > gap * gap;
  };
  if (region == kBlackRegion) {
    for (int e = 0; e < kElements; ++e) {
      if (!clear_of(e, geometry::kGreenOuterRadius)) return -1;
    }
    return region;
  }
  return clear_of((region - 2) / kCellsPerElement, geometry::kRedRadius) ? region : -1;
}

}  // namespace

RegionCoverage::RegionCoverage(const cv::Matx33d& tag_to_image, cv::Rect box) : box_(box) {
  if (box_.area() <= 0) return;
  const cv::Matx33d to_tag = tag_to_image.inv();
  coverage_.resize(static_cast<std::size_t>(box_.area()));
  parts_.reserve(coverage_.size() * 2);
  // Pixel corners in tag units, each shared by up to four pixels.
  const auto lattice_width = static_cast<std::size_t>(box_.width) + 1;
  std::vector<PixelCorner> corners(lattice_width * (static_cast<std::size_t>(box_.height) + 1));
  for (int ly = 0; ly <= box_.height; ++ly) {
    for (int lx = 0; lx <= box_.width; ++lx) {
      const cv::Vec3d t = to_tag * cv::Vec3d(box_.x + lx - 0.5, box_.y + ly - 0.5, 1);
      PixelCorner& corner =
          corners[static_cast<std::size_t>(ly) * lattice_width + static_cast<std::size_t>(lx)];
      corner.front = t[2] > 0;
      if (!corner.front) continue;
      corner.u = t[0] / t[2];
      corner.v = t[1] / t[2];
      corner.region = ModelRegionAt(corner.u, corner.v);
    }
  }
  std::array<int, kModelRegions> hits{};
  for (int gy = 0; gy < box_.height; ++gy) {
    for (int gx = 0; gx < box_.width; ++gx) {
      const double x = box_.x + gx, y = box_.y + gy;
      std::array<int, static_cast<std::size_t>(kSubsamples) * kSubsamples> touched{};
      std::size_t touched_count = 0;
      const std::size_t top_left =
          static_cast<std::size_t>(gy) * lattice_width + static_cast<std::size_t>(gx);
      const std::array<const PixelCorner*, 4> pixel_corners = {
          &corners[top_left], &corners[top_left + 1], &corners[top_left + lattice_width],
          &corners[top_left + lattice_width + 1]};
      const int whole_region = WholeRegion(pixel_corners);
      if (whole_region >= 0) {
        hits[static_cast<std::size_t>(whole_region)] = kSubsamples * kSubsamples;
        touched[touched_count++] = whole_region;
      }
      if (whole_region < 0) {
        // to_tag × (sub-sample x, y, 1), each row's products taken once per column and per row
        // of sub-samples and summed in the order the matrix product sums them (the same bits).
        std::array<std::array<double, kSubsamples>, 3> along_x{}, along_y{};
        for (int k = 0; k < kSubsamples; ++k) {
          const double sub_x = x - 0.5 + (k + 0.5) / kSubsamples;
          const double sub_y = y - 0.5 + (k + 0.5) / kSubsamples;
          for (int i = 0; i < 3; ++i) {
            along_x[static_cast<std::size_t>(i)][static_cast<std::size_t>(k)] =
                to_tag(i, 0) * sub_x;
            along_y[static_cast<std::size_t>(i)][static_cast<std::size_t>(k)] =
                to_tag(i, 1) * sub_y;
          }
        }
        for (std::size_t sy = 0; sy < kSubsamples; ++sy) {
          for (std::size_t sx = 0; sx < kSubsamples; ++sx) {
            const double w = along_x[2][sx] + along_y[2][sy] + to_tag(2, 2);
            int region = kQuietRegion;
            if (w > 0) {
              region = ModelRegionAt((along_x[0][sx] + along_y[0][sy] + to_tag(0, 2)) / w,
                                     (along_x[1][sx] + along_y[1][sy] + to_tag(1, 2)) / w);
            }
            if (hits[static_cast<std::size_t>(region)]++ == 0) touched[touched_count++] = region;
          }
        }
      }
      Coverage& c = coverage_[index(gx, gy)];
      c.first = static_cast<std::uint32_t>(parts_.size());
      c.count = static_cast<std::uint32_t>(touched_count);
      for (const int region : std::span(touched.data(), touched_count)) {
        parts_.push_back({region, static_cast<float>(hits[static_cast<std::size_t>(region)]) /
                                      (kSubsamples * kSubsamples)});
        hits[static_cast<std::size_t>(region)] = 0;
      }
    }
  }
  runs_.resize(coverage_.size());
  for (int gy = 0; gy < box_.height; ++gy) {
    for (int gx = box_.width - 1; gx >= 0; --gx) {
      const Coverage& c = coverage_[index(gx, gy)];
      if (c.count != 1) continue;
      const auto region = static_cast<std::uint8_t>(parts_[c.first].region);
      int length = 1;
      if (gx + 1 < box_.width) {
        const RegionRun& right = runs_[index(gx + 1, gy)];
        if (right.length > 0 && right.region == region) {
          length = std::min<int>(right.length + 1, std::numeric_limits<std::uint8_t>::max());
        }
      }
      runs_[index(gx, gy)] = {region, static_cast<std::uint8_t>(length)};
    }
  }
}

void RegionCoverage::blurred(const Kernel& kernel, int x, int y, SampleWeights& out) const {
  // Which regions were reached is kept as bits and listed once at the end: a test and a push per
  // tap made each addition wait on a branch (perf: a fifth of this function's time).
  static_assert(kModelRegions <= 64);
  std::uint64_t reached = 0;
  const auto add = [&](int region, double term) {
    out.weight[static_cast<std::size_t>(region)] += term;
    reached |= std::uint64_t{1} << region;
  };
  const int gx = x - box_.x, gy = y - box_.y;
  for (const KernelRow& row : kernel) {
    const std::size_t first = index(gx + row.dx_begin, gy + row.dy);
    const std::size_t count = row.weight.size();
    for (std::size_t j = 0; j < count;) {
      const RegionRun run = runs_[first + j];
      if (run.length > 0) {  // a stretch in one region: its weight in one addition
        const std::size_t end = std::min(count, j + run.length);
        add(run.region, row.prefix[end] - row.prefix[j]);
        j = end;
        continue;
      }
      const Coverage& c = coverage_[first + j];
      for (std::uint32_t k = 0; k < c.count; ++k) {
        const Part& part = parts_[c.first + k];
        add(part.region, row.weight[j] * part.weight);
      }
      ++j;
    }
  }
  for (; reached != 0; reached &= reached - 1) {
    const int region = std::countr_zero(reached);
    if (!out.listed[static_cast<std::size_t>(region)]) {
      out.listed[static_cast<std::size_t>(region)] = true;
      out.touched.push_back(region);
    }
  }
}

}  // namespace pintag::reading
