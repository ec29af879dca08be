#include "candidates/red_blobs.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <numeric>
#include <opencv2/imgproc.hpp>
#include <utility>

#include "candidates/lab_approx.hpp"
#include "candidates/least_r_table.hpp"

namespace pintag::stage {
namespace {

struct Moments {
  double n = 0, sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
  int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;

  void add(const RedRun& r) {
    const double a = r.x0, b = r.x1, count = b - a + 1, y = r.y;
    const auto s2 = [](double k) { return k * (k + 1) * (2 * k + 1) / 6; };
    const double sum_x = count * (a + b) / 2;
    n += count;
    sx += sum_x;
    sy += count * y;
    sxx += s2(b) - s2(a - 1);
    syy += count * y * y;
    sxy += sum_x * y;
    x0 = std::min(x0, r.x0), x1 = std::max(x1, r.x1), y0 = std::min(y0, r.y),
    y1 = std::max(y1, r.y);
  }
  void merge(const Moments& o) {
    n += o.n, sx += o.sx, sy += o.sy, sxx += o.sxx, syy += o.syy, sxy += o.sxy;
    x0 = std::min(x0, o.x0), x1 = std::max(x1, o.x1), y0 = std::min(y0, o.y0),
    y1 = std::max(y1, o.y1);
  }
};

int Find(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

bool ToBlob(const Moments& m, const BlobLimits& limits, RedBlob* blob) {
  const int area = static_cast<int>(m.n);
  if (area < limits.min_area || area > limits.max_area) return false;
  const double cx = m.sx / m.n, cy = m.sy / m.n;
  // Central second moments; + 1/12 because a pixel is a unit square, not a point.
  const double vxx = m.sxx / m.n - cx * cx + 1.0 / 12;
  const double vyy = m.syy / m.n - cy * cy + 1.0 / 12;
  const double vxy = m.sxy / m.n - cx * cy;
  const double mean = (vxx + vyy) / 2;
  const double diff = std::sqrt(std::max(0.0, (vxx - vyy) * (vxx - vyy) / 4 + vxy * vxy));
  const double l1 = mean + diff, l2 = std::max(mean - diff, 1e-6);
  blob->centroid = {cx, cy};
  blob->area = area;
  blob->major = 4 * std::sqrt(l1);  // an ellipse with semi-axis a has variance a²/4
  blob->minor = 4 * std::sqrt(l2);
  blob->fill = area / (std::numbers::pi / 4 * blob->major * blob->minor);
  blob->box = cv::Rect(m.x0, m.y0, m.x1 - m.x0 + 1, m.y1 - m.y0 + 1);
  blob->angle = 0.5 * std::atan2(2 * vxy, vxx - vyy);
  if (blob->fill < limits.min_fill || blob->fill > 1.0 / limits.min_fill) return false;
  return blob->major <= limits.max_elongation * blob->minor;
}

}  // namespace

bool IsRingColourByLabApprox(int r, int g, int b) {
  const LabApprox& lab = LabApprox::Get();
  int a_star, b_star;
  lab.abStar(r, g, b, &a_star, &b_star);
  return a_star < 10 * kLabScale && lab.lStar(r, g, b) < 85 * kLabScale;
}

bool IsRingColour(int r, int g, int b) {
  // Not ring = a* >= 10 or L* >= 85: both grow with R, so that is upward-closed in R and the
  // least such R for each (G, B) decides. A blob's ring test looks up about a dozen colours, and
  // a frame has hundreds of blobs: the lookup costs 0.13 ms a load scene where LabApprox cost 0.45.
  static const std::vector<std::uint16_t> least_not_ring = LeastRTable(
      [](int red, int green, int blue) { return !IsRingColourByLabApprox(red, green, blue); });
  return r < least_not_ring[static_cast<std::size_t>((g << 8) | b)];
}

bool HasRing(const cv::Mat& bgr, const RedBlob& blob) {
  // The eight directions, every 45°, as (cos, sin).
  static const std::array<std::pair<double, double>, 8> kDirections = [] {
    std::array<std::pair<double, double>, 8> d;
    for (std::size_t k = 0; k < d.size(); ++k) {
      const double t = static_cast<double>(k) * std::numbers::pi / 4;
      d[k] = {std::cos(t), std::sin(t)};
    }
    return d;
  }();
  const double ca = std::cos(blob.angle), sa = std::sin(blob.angle);
  // 1.5 × the semi-axes lands in the green ring when the blob is the whole red disk. A blurred
  // small disk passes the redness test only in its core, and there 1.5 × is still red: look
  // further out too (2.5 ×, 3.5 ×); red marks on white paper and orange textures fail at every
  // radius.
  for (const double scale : {0.75, 1.25, 1.75}) {
    const double ra = scale * blob.major, rb = scale * blob.minor;
    // Five of the eight points must be ring: stop as soon as that is reached or out of reach.
    int ring = 0;
    for (int k = 0; k < 8 && ring < 5 && ring + (8 - k) >= 5; ++k) {
      const auto [cos_t, sin_t] = kDirections[static_cast<std::size_t>(k)];
      const double u = ra * cos_t, v = rb * sin_t;
      const int x = static_cast<int>(std::lround(blob.centroid.x + u * ca - v * sa));
      const int y = static_cast<int>(std::lround(blob.centroid.y + u * sa + v * ca));
      if (x < 0 || y < 0 || x >= bgr.cols || y >= bgr.rows) continue;
      const std::uint8_t* p = bgr.ptr<std::uint8_t>(y) + 3 * static_cast<std::ptrdiff_t>(x);
      ring += IsRingColour(p[2], p[1], p[0]);
    }
    if (ring >= 5) return true;
  }
  return false;
}

std::vector<RedBlob> FindRedBlobs(const RedRuns& red, const BlobLimits& limits) {
  const std::vector<RedRun>& runs = red.runs;
  const int n = static_cast<int>(runs.size());
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  // Runs of consecutive rows touch (8-connectivity) when their spans overlap once widened by 1.
  int prev_begin = 0, prev_end = 0;  // runs of the previous row: [prev_begin, prev_end)
  for (int i = 0; i < n;) {
    const int y = runs[i].y;
    int end = i;
    while (end < n && runs[end].y == y) ++end;
    const bool adjacent = prev_end > prev_begin && runs[prev_begin].y == y - 1;
    if (adjacent) {
      int j = prev_begin;
      for (int k = i; k < end; ++k) {
        while (j < prev_end && runs[j].x1 < runs[k].x0 - 1) ++j;
        for (int m = j; m < prev_end && runs[m].x0 <= runs[k].x1 + 1; ++m) {
          parent[Find(parent, k)] = Find(parent, m);
        }
      }
    }
    prev_begin = i;
    prev_end = end;
    i = end;
  }
  std::vector<int> slot(n, -1);
  std::vector<Moments> moments;
  for (int i = 0; i < n; ++i) {
    const int root = Find(parent, i);
    if (slot[root] < 0) {
      slot[root] = static_cast<int>(moments.size());
      moments.emplace_back();
    }
    moments[slot[root]].add(runs[i]);
  }
  std::vector<RedBlob> blobs;
  for (const Moments& m : moments) {
    RedBlob blob;
    if (ToBlob(m, limits, &blob)) blobs.push_back(blob);
  }
  if (static_cast<int>(blobs.size()) > limits.max_blobs) {
    std::nth_element(blobs.begin(), blobs.begin() + limits.max_blobs, blobs.end(),
                     [](const RedBlob& a, const RedBlob& b) { return a.area > b.area; });
    blobs.resize(limits.max_blobs);
  }
  return blobs;
}

std::vector<RedBlob> FindRedBlobs(const cv::Mat& mask, const BlobLimits& limits) {
  RedRuns red;
  red.size = mask.size();
  for (int y = 0; y < mask.rows; ++y) {
    const std::uint8_t* row = mask.ptr<std::uint8_t>(y);
    for (int x = 0; x < mask.cols;) {
      if (!row[x]) {
        ++x;
        continue;
      }
      const int start = x;
      while (x < mask.cols && row[x]) ++x;
      red.runs.push_back({y, start, x - 1});
    }
  }
  return FindRedBlobs(red, limits);
}

}  // namespace pintag::stage
