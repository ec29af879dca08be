#include "reading/tag_samples.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <opencv2/imgproc.hpp>

namespace pintag::reading {
namespace {

bool WithinMargin(const cv::Matx33d& to_tag, double x, double y) {
  const cv::Vec3d t = to_tag * cv::Vec3d(x, y, 1);
  if (!(t[2] > 0)) return false;
  const double u = t[0] / t[2], v = t[1] / t[2];
  return u >= -kObservedMargin && u <= 1 + kObservedMargin && v >= -kObservedMargin &&
         v <= 1 + kObservedMargin;
}

const std::array<double, 256>& LinearTable() {
  static const std::array<double, 256> table = [] {
    std::array<double, 256> t{};
    for (int i = 0; i < 256; ++i) {
      const double v = i / 255.0;
      t[static_cast<std::size_t>(i)] =
          v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
    }
    return t;
  }();
  return table;
}

double Luminance(const std::uint8_t* bgr) {
  const auto& lin = LinearTable();
  return 0.2126 * lin[bgr[2]] + 0.7152 * lin[bgr[1]] + 0.0722 * lin[bgr[0]];
}

// BT.601, full range, as JPEG: Cb = (B′ − Y′) / 1.772, Cr = (R′ − Y′) / 1.402.
constexpr double kCb = 0.5 / (1 - 0.114), kCr = 0.5 / (1 - 0.299);

}  // namespace

void UndoChromaUpsampling(cv::Mat* block_means, ChromaUpsampling upsampling) {
  const bool across =
      upsampling == ChromaUpsampling::kBoth || upsampling == ChromaUpsampling::kAcross;
  const bool down = upsampling == ChromaUpsampling::kBoth || upsampling == ChromaUpsampling::kDown;
  if ((!across && !down) || (across && block_means->cols < 3) || (down && block_means->rows < 3)) {
    return;
  }
  // The mean of a block's upsampled pixels is this kernel over the stored samples. Jacobi steps
  // towards its inverse: the kernel's centre (36 / 64, or 6 / 8 along one axis) outweighs the
  // rest.
  const cv::Mat blur = (cv::Mat_<double>(3, 1) << 1, 6, 1) / 8.0;
  const cv::Mat identity = (cv::Mat_<double>(3, 1) << 0, 1, 0);
  const cv::Mat& along_x = across ? blur : identity;
  const cv::Mat& along_y = down ? blur : identity;
  const double centre = along_x.at<double>(1) * along_y.at<double>(1);
  const cv::Mat means = block_means->clone();
  cv::Mat blurred;
  for (int step = 0; step < kUndoUpsamplingSteps; ++step) {
    cv::sepFilter2D(*block_means, blurred, CV_64F, along_x, along_y, cv::Point(-1, -1), 0,
                    cv::BORDER_REPLICATE);
    *block_means += (means - blurred) / centre;
  }
}

TagSamples SampleTag(const cv::Mat& bgr, ChromaUpsampling upsampling,
                     const cv::Matx33d& tag_to_image, int border) {
  TagSamples samples;
  double x0 = 1e18, y0 = 1e18, x1 = -1e18, y1 = -1e18;
  for (const double u : {-kObservedMargin, 1 + kObservedMargin}) {
    for (const double v : {-kObservedMargin, 1 + kObservedMargin}) {
      const cv::Vec3d p = tag_to_image * cv::Vec3d(u, v, 1);
      if (!(p[2] > 0)) return samples;
      x0 = std::min(x0, p[0] / p[2]), x1 = std::max(x1, p[0] / p[2]);
      y0 = std::min(y0, p[1] / p[2]), y1 = std::max(y1, p[1] / p[2]);
    }
  }
  const cv::Rect inside(border, border, bgr.cols - 2 * border, bgr.rows - 2 * border);
  cv::Rect box(static_cast<int>(std::floor(x0)), static_cast<int>(std::floor(y0)), 0, 0);
  box.width = static_cast<int>(std::ceil(x1)) + 1 - box.x;
  box.height = static_cast<int>(std::ceil(y1)) + 1 - box.y;
  box &= inside;
  if (box.area() <= 0 || box.area() > 4'000'000) return samples;
  const cv::Matx33d to_tag = tag_to_image.inv();
  for (int y = box.y; y < box.y + box.height; ++y) {
    const std::uint8_t* row = bgr.ptr<std::uint8_t>(y);
    for (int x = box.x; x < box.x + box.width; ++x) {
      if (WithinMargin(to_tag, x, y)) {
        samples.luma.push_back({x, y, Luminance(row + (3 * static_cast<std::ptrdiff_t>(x)))});
      }
    }
  }
  // Blocks at even coordinates wholly inside: their centre decides. Every block of the box is
  // averaged first, so that the upsampling can be undone across the box.
  const int bx0 = box.x + (box.x & 1), by0 = box.y + (box.y & 1);
  const int blocks_x = (box.x + box.width - bx0) / 2, blocks_y = (box.y + box.height - by0) / 2;
  if (blocks_x <= 0 || blocks_y <= 0) return samples;
  cv::Mat cb(blocks_y, blocks_x, CV_64F), cr(blocks_y, blocks_x, CV_64F);
  for (int by = 0; by < blocks_y; ++by) {
    for (int bx = 0; bx < blocks_x; ++bx) {
      const int x = bx0 + 2 * bx, y = by0 + 2 * by;
      double sum_cb = 0, sum_cr = 0;
      for (int dy = 0; dy < 2; ++dy) {
        const std::uint8_t* p =
            bgr.ptr<std::uint8_t>(y + dy) + (3 * static_cast<std::ptrdiff_t>(x));
        for (int dx = 0; dx < 2; ++dx, p += 3) {
          const double luma = (0.299 * p[2] + 0.587 * p[1] + 0.114 * p[0]) / 255.0;
          sum_cb += kCb * (p[0] / 255.0 - luma);
          sum_cr += kCr * (p[2] / 255.0 - luma);
        }
      }
      cb.at<double>(by, bx) = sum_cb / 4;
      cr.at<double>(by, bx) = sum_cr / 4;
    }
  }
  UndoChromaUpsampling(&cb, upsampling);
  UndoChromaUpsampling(&cr, upsampling);
  for (int by = 0; by < blocks_y; ++by) {
    for (int bx = 0; bx < blocks_x; ++bx) {
      const int x = bx0 + 2 * bx, y = by0 + 2 * by;
      if (!WithinMargin(to_tag, x + 0.5, y + 0.5)) continue;
      samples.chroma.push_back({x, y, cb.at<double>(by, bx), cr.at<double>(by, bx)});
    }
  }
  samples.bounds = box;
  return samples;
}

}  // namespace pintag::reading
