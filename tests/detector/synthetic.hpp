#pragma once
// A small warp-based scene maker for the detector's unit tests: a real rendered tag placed with a
// pose in a pinhole camera over a procedural background, supersampled, optionally blurred and
// noised. (The full scene generator with photographs and photometry is pintag::scene.)

#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

namespace pintag::testing {

struct SyntheticCamera {
  double f = 1200;
  int width = 960;
  int height = 540;
  cv::Matx33d cameraMatrix() const {
    return {f, 0, (width - 1) / 2.0, 0, f, (height - 1) / 2.0, 0, 0, 1};
  }
};

struct SyntheticTag {
  int key = 0;
  cv::Point2d centre_px{480, 270};  ///< where the square's centre appears
  double square_px = 120;           ///< side the square would have seen frontally, px
  double tilt_deg = 0;              ///< rotation about the tilt axis
  double tilt_axis_deg = 0;         ///< in-plane direction of the tilt axis
  double roll_deg = 0;              ///< in-plane rotation
  int occluded_element = -1;        ///< 0 … 3: cover that element with a beige disk
};

struct SyntheticTruth {
  int key = 0;
  std::array<cv::Point2d, 4> corners;
  cv::Matx33d rotation;
  cv::Vec3d translation;  ///< metres, for a 50 mm tag
};

struct SyntheticScene {
  cv::Mat bgr;
  std::vector<SyntheticTruth> truth;
};

struct SyntheticOptions {
  SyntheticCamera camera;
  std::uint64_t seed = 1;
  double blur_sigma = 0;
  double noise_sigma = 0;
  bool red_distractors = false;  ///< red disks and shapes in the background
  int supersample = 3;
};

SyntheticScene MakeScene(const std::vector<SyntheticTag>& tags, const SyntheticOptions& options);

}  // namespace pintag::testing
