// Marker textures: PinTag from the project's renderer, ArUco DICT_5X5_1000, AprilTag tag36h10, all
// with the same black-square convention and a white quiet zone of 0.15 of the square.

#include <apriltag/apriltag.h>
#include <apriltag/tag36h10.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <memory>
#include <mutex>
#include <opencv2/aruco.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <utility>

#include "pintag/codec/geometry.hpp"
#include "pintag/codec/palette.hpp"
#include "pintag/codec/tag_raster.hpp"
#include "pintag/scene/scene.hpp"

namespace pintag::scene {
namespace {

/// Wraps a black square image (its whole extent is the square) in the white quiet zone.
MarkerTexture WithQuietZone(const cv::Mat& square_bgr) {
  const int n = square_bgr.cols;
  const int margin = QuietZonePx(n);
  MarkerTexture texture;
  cv::copyMakeBorder(square_bgr, texture.bgr, margin, margin, margin, margin, cv::BORDER_CONSTANT,
                     cv::Scalar(255, 255, 255));
  const double lo = margin - 0.5, hi = margin + n - 0.5;
  texture.square_corners_px = {cv::Point2d(lo, lo), cv::Point2d(hi, lo), cv::Point2d(hi, hi),
                               cv::Point2d(lo, hi)};
  return texture;
}

/// Binary cells (0 = black) → the palette's black and white, each cell `cell_px` pixels.
cv::Mat PrintCells(const cv::Mat& cells_u8, int cell_px) {
  cv::Mat big;
  cv::resize(cells_u8, big, cv::Size(), cell_px, cell_px, cv::INTER_NEAREST);
  const Rgb8 black = SrgbFor(PaletteColour::kBlack);
  cv::Mat bgr(big.size(), CV_8UC3);
  for (int y = 0; y < big.rows; ++y) {
    for (int x = 0; x < big.cols; ++x) {
      bgr.at<cv::Vec3b>(y, x) = big.at<std::uint8_t>(y, x) < 128
                                    ? cv::Vec3b(black.b, black.g, black.r)
                                    : cv::Vec3b(255, 255, 255);
    }
  }
  return bgr;
}

}  // namespace

MarkerTexture PinTagTexture(int key, int square_px) {
  if (!TagKey::IsValid(key)) throw std::invalid_argument("PinTagTexture: key out of range");
  TagRasterOptions options;
  options.square_px = std::max(square_px, kMinTagSquarePx);
  // The scene supersamples again and samples the texture bilinearly, so the renderer's own
  // anti-aliasing matters only for small textures; skipping it at 256 px and up is 4 times faster.
  options.supersample = options.square_px >= 256 ? 1 : 2;

  static std::mutex mutex;
  static std::deque<std::pair<std::pair<int, int>, MarkerTexture>> cache;  // newest first
  constexpr std::size_t kCacheSize = 64;
  const std::pair<int, int> id(key, options.square_px);
  {
    const std::lock_guard lock(mutex);
    for (const auto& [cached_id, cached] : cache) {
      if (cached_id == id) return {cached.bgr.clone(), cached.square_corners_px};
    }
  }

  const TagRaster raster = RenderTagRaster(TagKey(static_cast<std::uint16_t>(key)), options);
  const RgbImage& image = raster.image;
  MarkerTexture texture;
  texture.bgr.create(image.height, image.width, CV_8UC3);
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      const Rgb8 c = image.at(x, y);
      texture.bgr.at<cv::Vec3b>(y, x) = cv::Vec3b(c.b, c.g, c.r);
    }
  }
  const double lo = raster.square_origin_px - 0.5, hi = lo + raster.square_px;
  texture.square_corners_px = {cv::Point2d(lo, lo), cv::Point2d(hi, lo), cv::Point2d(hi, hi),
                               cv::Point2d(lo, hi)};
  const std::lock_guard lock(mutex);
  cache.emplace_front(id, MarkerTexture{texture.bgr.clone(), texture.square_corners_px});
  if (cache.size() > kCacheSize) cache.pop_back();
  return texture;
}

MarkerTexture ArucoTexture(int id, int square_px) {
  constexpr int kCells = 7;  // 5 × 5 bits and a one-cell black border
  const cv::Ptr<cv::aruco::Dictionary> dictionary =
      cv::aruco::getPredefinedDictionary(cv::aruco::DICT_5X5_1000);
  if (id < 0 || id >= dictionary->bytesList.rows) {
    throw std::invalid_argument("ArucoTexture: id out of range");
  }
  cv::Mat cells;
  cv::aruco::drawMarker(dictionary, id, kCells, cells, 1);
  const int cell_px = std::max(1, static_cast<int>(std::lround(square_px / double(kCells))));
  return WithQuietZone(PrintCells(cells, cell_px));
}

MarkerTexture AprilTagTexture(int id, int square_px) {
  const std::unique_ptr<apriltag_family_t, void (*)(apriltag_family_t*)> family(tag36h10_create(),
                                                                                tag36h10_destroy);
  if (id < 0 || id >= static_cast<int>(family->ncodes)) {
    throw std::invalid_argument("AprilTagTexture: id out of range");
  }
  const std::unique_ptr<image_u8_t, void (*)(image_u8_t*)> image(
      apriltag_to_image(family.get(), id), image_u8_destroy);
  // The family's image has a white ring around the black border; keep only the black square.
  const int n = family->width_at_border;
  const int offset = (family->total_width - n) / 2;
  cv::Mat cells(n, n, CV_8UC1);
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      cells.at<std::uint8_t>(y, x) = image->buf[(y + offset) * image->stride + x + offset];
    }
  }
  const int cell_px = std::max(1, static_cast<int>(std::lround(square_px / double(n))));
  return WithQuietZone(PrintCells(cells, cell_px));
}

Occluder CoverElement(int element) {
  if (element < 0 || element >= kElements) {
    throw std::invalid_argument("CoverElement: element not 0 … 3");
  }
  const geometry::Point centre = geometry::kElementCentres[element];
  Occluder occluder;
  occluder.centre = {centre.x, centre.y};
  occluder.radius = geometry::kGreenOuterRadius + 0.025;  // 0.025 short of the square's edges
  return occluder;
}

}  // namespace pintag::scene
