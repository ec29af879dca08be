#include "debug_images.hpp"

#include <cstdint>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "pintag/codec/file_output.hpp"
#include "pintag/detector/tag_outline.hpp"

namespace pintag::stage {

namespace {

/// `image` as a PNG file at `path`: "" when written, else why not. Encoded in memory and written
/// whole because cv::imwrite does not check its file's close (WriteWholeFile).
std::string WritePngFile(const std::string& path, const cv::Mat& image) {
  std::vector<std::uint8_t> bytes;
  try {
    if (!cv::imencode(".png", image, bytes)) return "cannot encode it";
  } catch (const cv::Exception& e) {
    return e.what();
  }
  return WriteWholeFile(
      path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

}  // namespace

void DebugImages::write(const std::string& name, const cv::Mat& image) const {
  // Kept, not thrown: a stage image is a by-product, and the detector reports it once at the end
  // (DetectResult::error) rather than leave the caller believing the images are there.
  const std::string path = (std::filesystem::path(dir_) / name).string();
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  const std::string why = ec ? ec.message() : WritePngFile(path, image);
  if (why.empty()) return;
  const std::lock_guard<std::mutex> lock(mutex_);
  if (failure_.empty()) failure_ = "cannot write debug image " + path + ": " + why;
}

std::string DebugImages::failure() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return failure_;
}

void DebugImages::redness(const cv::Mat& mask) const {
  if (enabled()) write(kDebugImageNames[0], mask);
}

void DebugImages::blobs(const cv::Mat& bgr, const std::vector<RedBlob>& blobs,
                        const std::vector<BlobCluster>& clusters) const {
  if (!enabled()) return;
  cv::Mat out = bgr / 2;
  for (const RedBlob& b : blobs) cv::rectangle(out, b.box, {0, 255, 255}, 1);
  for (const BlobCluster& c : clusters) cv::rectangle(out, c.roi, {255, 128, 0}, 2);
  write(kDebugImageNames[1], out);
}

void DebugImages::quads(const cv::Mat& bgr, const std::vector<Quad>& quads) const {
  if (!enabled()) return;
  cv::Mat out = bgr / 2;
  for (const Quad& q : quads) {
    for (int i = 0; i < 4; ++i) cv::line(out, q[i], q[(i + 1) % 4], {0, 255, 0}, 1, cv::LINE_AA);
  }
  write(kDebugImageNames[2], out);
}

void DebugImages::detections(const cv::Mat& bgr, const std::vector<Detection>& detections) const {
  if (!enabled()) return;
  cv::Mat out = bgr.clone();
  for (const Detection& d : detections) {
    const cv::Scalar colour = d.key ? cv::Scalar(0, 255, 0) : cv::Scalar(0, 0, 255);
    DrawTagOutline(out, d, colour, d.key ? std::to_string(d.key->value()) : d.reject_reason);
  }
  write(kDebugImageNames[3], out);
}

}  // namespace pintag::stage
