#pragma once
// DetectorOptions::debug_dir: each stage writes an image there, numbered in pipeline order.

#include <mutex>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "candidates/grouping.hpp"
#include "candidates/quads.hpp"
#include "candidates/red_blobs.hpp"
#include "pintag/detector/detection.hpp"

namespace pintag::stage {

class DebugImages {
 public:
  explicit DebugImages(std::string dir) : dir_(std::move(dir)) {}
  bool enabled() const { return !dir_.empty(); }

  void redness(const cv::Mat& mask) const;
  void blobs(const cv::Mat& bgr, const std::vector<RedBlob>& blobs,
             const std::vector<BlobCluster>& clusters) const;
  void quads(const cv::Mat& bgr, const std::vector<Quad>& quads) const;
  void detections(const cv::Mat& bgr, const std::vector<Detection>& detections) const;

  /// The first image that could not be written, with why; empty while every one was.
  std::string failure() const;

 private:
  void write(const std::string& name, const cv::Mat& image) const;
  std::string dir_;
  mutable std::mutex mutex_;  ///< guards failure_: stages may write from worker threads
  mutable std::string failure_;
};

}  // namespace pintag::stage
