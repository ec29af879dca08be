#include "debug_images.hpp"

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "pintag/detector/tag_outline.hpp"

namespace pintag::stage {

void DebugImages::write(const std::string& name, const cv::Mat& image) const {
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  cv::imwrite((std::filesystem::path(dir_) / name).string(), image);
}

void DebugImages::redness(const cv::Mat& mask) const {
  if (enabled()) write("1_redness.png", mask);
}

void DebugImages::blobs(const cv::Mat& bgr, const std::vector<RedBlob>& blobs,
                        const std::vector<BlobCluster>& clusters) const {
  if (!enabled()) return;
  cv::Mat out = bgr / 2;
  for (const RedBlob& b : blobs) cv::rectangle(out, b.box, {0, 255, 255}, 1);
  for (const BlobCluster& c : clusters) cv::rectangle(out, c.roi, {255, 128, 0}, 2);
  write("2_blobs.png", out);
}

void DebugImages::quads(const cv::Mat& bgr, const std::vector<Quad>& quads) const {
  if (!enabled()) return;
  cv::Mat out = bgr / 2;
  for (const Quad& q : quads) {
    for (int i = 0; i < 4; ++i) cv::line(out, q[i], q[(i + 1) % 4], {0, 255, 0}, 1, cv::LINE_AA);
  }
  write("3_quads.png", out);
}

void DebugImages::detections(const cv::Mat& bgr, const std::vector<Detection>& detections) const {
  if (!enabled()) return;
  cv::Mat out = bgr.clone();
  for (const Detection& d : detections) {
    const cv::Scalar colour = d.key ? cv::Scalar(0, 255, 0) : cv::Scalar(0, 0, 255);
    DrawTagOutline(out, d, colour, d.key ? std::to_string(d.key->value()) : d.reject_reason);
  }
  write("4_detections.png", out);
}

}  // namespace pintag::stage
