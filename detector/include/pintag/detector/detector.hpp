#pragma once
// The front door: pintag::Detector{options}.detect(image).
//
//   auto loaded = pintag::LoadImageFile("photo.jpg");
//   if (!loaded.image) error(loaded.error);
//   pintag::Detector detector({.tag_size_m = 0.05});
//   for (const auto& tag : detector.detect(*loaded.image).detections) use(*tag.key, tag.pose);

#include <opencv2/core.hpp>

#include "pintag/detector/chroma_upsampling.hpp"
#include "pintag/detector/detection.hpp"
#include "pintag/detector/image_io.hpp"
#include "pintag/detector/options.hpp"

namespace pintag {

class Detector {
 public:
  explicit Detector(DetectorOptions options = {});

  /// Finds every tag in an 8-bit BGR image (CV_8UC3) whose colour was decoded with `upsampling`
  /// (kNone for pixels whose colour was never subsampled: renders, PNG, 4:4:4 JPEG). `exif` feeds
  /// the camera model when no intrinsics were given. An empty or wrongly typed image gives a
  /// result with `error` set.
  DetectResult detect(const cv::Mat& bgr, const ExifCamera* exif,
                      ChromaUpsampling upsampling) const;
  /// Same for pixels of unknown origin: taken as a decoded 4:2:0 JPEG, what phones save.
  DetectResult detect(const cv::Mat& bgr, const ExifCamera* exif = nullptr) const;
  /// Same for an image loaded with LoadImageFile / LoadImageBytes (EXIF and the decoder's chroma
  /// upsampling used).
  DetectResult detect(const LoadedImage& image) const;

  const DetectorOptions& options() const { return options_; }

 private:
  DetectorOptions options_;
};

std::string_view ToString(IntrinsicsSource source);

}  // namespace pintag
