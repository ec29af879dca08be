#include "reading/sampling.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "candidates/lab_approx.hpp"
#include "pintag/codec/geometry.hpp"

namespace pintag::stage {
namespace {

// Sample positions inside a cell, kept well away from its borders so that blur and a slightly
// wrong homography still land on the cell's own colour.
constexpr double kGreenRadii[] = {0.135, 0.15, 0.165};
constexpr double kGreenAngles[] = {-6, 0, 6};  // degrees around the sector's mid-angle
constexpr double kRedRadii[] = {0.05, 0.065};
constexpr double kRedAngles[] = {-8, 0, 8};

bool SampleRgb(const cv::Mat& bgr, cv::Point2d p, int rgb[3]) {
  const int x0 = static_cast<int>(std::floor(p.x)), y0 = static_cast<int>(std::floor(p.y));
  if (x0 < 0 || y0 < 0 || x0 + 1 >= bgr.cols || y0 + 1 >= bgr.rows) return false;
  const int fx = static_cast<int>((p.x - x0) * 256), fy = static_cast<int>((p.y - y0) * 256);
  const std::uint8_t* r0 = bgr.ptr<std::uint8_t>(y0) + 3 * static_cast<std::ptrdiff_t>(x0);
  const std::uint8_t* r1 = bgr.ptr<std::uint8_t>(y0 + 1) + 3 * static_cast<std::ptrdiff_t>(x0);
  for (int c = 0; c < 3; ++c) {
    const int top = r0[c] * (256 - fx) + r0[c + 3] * fx;
    const int bottom = r1[c] * (256 - fx) + r1[c + 3] * fx;
    rgb[2 - c] = (top * (256 - fy) + bottom * fy + (1 << 15)) >> 16;
  }
  return true;
}

double Median(std::vector<double>& v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : (v[n / 2 - 1] + v[n / 2]) / 2;
}

template <std::size_t R, std::size_t A>
CellSample SampleCell(const cv::Mat& bgr, const cv::Matx33d& h, geometry::Point centre,
                      double mid_angle, const double (&radii)[R], const double (&angles)[A]) {
  const LabApprox& lab = LabApprox::Get();
  std::vector<double> as, bs;
  as.reserve(R * A);
  bs.reserve(R * A);
  for (double r : radii) {
    for (double da : angles) {
      const geometry::Point d = geometry::Direction(mid_angle + da);
      const double u = centre.x + r * d.x, v = centre.y + r * d.y;
      const cv::Vec3d p = h * cv::Vec3d(u, v, 1);
      int rgb[3];
      if (!SampleRgb(bgr, {p[0] / p[2], p[1] / p[2]}, rgb)) return {};
      int a, b;
      lab.abStar(rgb[0], rgb[1], rgb[2], &a, &b);
      as.push_back(static_cast<double>(a) / kLabScale);
      bs.push_back(static_cast<double>(b) / kLabScale);
    }
  }
  CellSample s;
  s.b_spread = *std::max_element(bs.begin(), bs.end()) - *std::min_element(bs.begin(), bs.end());
  s.a = Median(as);
  s.b = Median(bs);
  s.valid = true;
  return s;
}

}  // namespace

CellSamples SampleCells(const cv::Mat& bgr, const cv::Matx33d& tag_to_image) {
  CellSamples cells;
  for (int e = 0; e < kElements; ++e) {
    const geometry::Point c = geometry::kElementCentres[e];
    for (int s = 0; s < kGreenSectors; ++s) {
      cells.green[e][s] =
          SampleCell(bgr, tag_to_image, c, 45.0 * s + 22.5, kGreenRadii, kGreenAngles);
    }
    for (int q = 0; q < kRedQuadrants; ++q) {
      cells.red[e][q] = SampleCell(bgr, tag_to_image, c, 90.0 * q + 45.0, kRedRadii, kRedAngles);
    }
  }
  return cells;
}

}  // namespace pintag::stage
