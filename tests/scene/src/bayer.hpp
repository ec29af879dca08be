#pragma once
// A Bayer colour filter array's layout, shared by both worlds' sensors (the tuning world's
// photometry.cpp and the held-out phone_capture.cpp): which colour each pixel keeps, and OpenCV's
// name for the pattern. The worlds differ in what surrounds it, not in this fact.

#include <array>
#include <cstddef>
#include <opencv2/imgproc.hpp>

namespace pintag::scene::detail {

/// BGR index (0 B, 1 G, 2 R) of the colour pixel (x, y) keeps under `phase` (0 RGGB, 1 GRBG,
/// 2 GBRG, 3 BGGR: where R sits in each 2 × 2 cell).
inline int BayerChannel(int x, int y, int phase) {
  const int rx = phase == 1 || phase == 3 ? 1 : 0;
  const int ry = phase >= 2 ? 1 : 0;
  const bool r_row = ((y ^ ry) & 1) == 0, r_col = ((x ^ rx) & 1) == 0;
  return r_row ? (r_col ? 2 : 1) : (r_col ? 1 : 0);
}

/// OpenCV's demosaic code for `phase`, bilinear or (`edge_aware`) edge-aware. OpenCV names a
/// pattern by the second row's second and third pixels: RGGB is "BayerBG".
inline int BayerDemosaicCode(int phase, bool edge_aware) {
  constexpr std::array<int, 4> kBilinear = {cv::COLOR_BayerBG2BGR, cv::COLOR_BayerGB2BGR,
                                            cv::COLOR_BayerGR2BGR, cv::COLOR_BayerRG2BGR};
  constexpr std::array<int, 4> kEdgeAware = {cv::COLOR_BayerBG2BGR_EA, cv::COLOR_BayerGB2BGR_EA,
                                             cv::COLOR_BayerGR2BGR_EA, cv::COLOR_BayerRG2BGR_EA};
  const auto i = static_cast<std::size_t>(phase & 3);
  return edge_aware ? kEdgeAware[i] : kBilinear[i];
}

/// OpenCV's variable-number-of-gradients demosaic code for `phase` (8-bit only): edge-directed,
/// like a phone's and unlike the bilinear one, yet not the held-out phone's edge-aware method.
inline int BayerVngDemosaicCode(int phase) {
  constexpr std::array<int, 4> kVng = {cv::COLOR_BayerBG2BGR_VNG, cv::COLOR_BayerGB2BGR_VNG,
                                       cv::COLOR_BayerGR2BGR_VNG, cv::COLOR_BayerRG2BGR_VNG};
  return kVng[static_cast<std::size_t>(phase & 3)];
}

}  // namespace pintag::scene::detail
