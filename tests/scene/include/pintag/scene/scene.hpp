#pragma once
// Synthetic camera scenes with ground truth, for detector tests and the benchmark.
//
// A marker texture (a PinTag from the real renderer, or an ArUco / AprilTag marker) is placed with
// a known pose in front of a known pinhole camera, over a background (a real photograph from a
// Debian package where one is installed, procedural otherwise), then degraded: supersampled
// anti-aliasing, lighting gradient, colour cast, defocus and motion blur, sensor noise, JPEG.
// Everything is deterministic for a given seed.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace pintag::scene {

/// Pinhole camera without distortion, pixels.
struct Camera {
  double fx = 1400, fy = 1400, cx = 960, cy = 540;
  int width = 1920, height = 1080;
};

/// A marker image and where its black square (the part whose side is `square_side_m`) lies in it:
/// the square's four corners in texture pixels, C0 top-left then clockwise. The rest of the
/// texture (quiet zone) is drawn too.
struct MarkerTexture {
  cv::Mat bgr;  ///< CV_8UC3
  std::array<cv::Point2d, 4> square_corners_px;
};

/// Pose of the marker's square in the camera frame: x right, y down, z forward (OpenCV
/// convention). The square's model points are (±s/2, ±s/2, 0) with C0 = (−s/2, −s/2, 0).
struct Pose {
  cv::Matx33d rotation = cv::Matx33d::eye();
  cv::Vec3d translation{0, 0, 1};
};

/// Pose from viewing parameters: distance (m) of the square's centre along the ray through
/// image point `centre_px`, tilt (degrees, 0 = facing the camera) about an axis in the square's
/// plane at `tilt_axis_deg`, and in-plane rotation `roll_deg`.
Pose MakePose(const Camera& camera, cv::Point2d centre_px, double distance_m, double tilt_deg,
              double tilt_axis_deg, double roll_deg);

enum class Cast { kNone, kTungsten, kFluorescent, kShade };

struct Photometry {
  double gradient = 0;         ///< brightness falloff across the frame, 0 … 0.6
  Cast cast = Cast::kNone;
  double defocus_sigma_px = 0;  ///< Gaussian blur sigma
  double motion_px = 0;         ///< motion blur length
  double noise_sigma = 0;       ///< sensor noise, 8-bit code values
  int jpeg_quality = 0;         ///< 0 = no JPEG round trip, else 1 … 100
  double exposure = 1.0;        ///< overall gain
  static Photometry Moderate(std::uint64_t seed);  ///< random mild settings
  static Photometry Hard(std::uint64_t seed);      ///< random harsh settings
};

struct PlacedMarker {
  MarkerTexture texture;
  double square_side_m = 0.05;
  Pose pose;
  int id = -1;  ///< the truth this marker carries (PinTag key, ArUco / AprilTag id)
};

struct SceneSpec {
  Camera camera;
  std::vector<PlacedMarker> markers;
  Photometry photometry;
  std::uint64_t seed = 1;  ///< background choice and noise
  bool real_background = true;  ///< use a photograph where one is installed
};

struct MarkerTruth {
  int id = -1;
  std::array<cv::Point2d, 4> corners_px;  ///< projected square corners, C0 … C3
  Pose pose;
  double square_px = 0;  ///< mean projected side length
  bool fully_visible = true;
};

struct Scene {
  cv::Mat bgr;  ///< CV_8UC3, camera.width × camera.height
  std::vector<MarkerTruth> truth;
  std::string background;  ///< which background was used (file name or "procedural")
};

Scene RenderScene(const SceneSpec& spec);

/// A PinTag texture for `key` from the project's renderer (square `square_px` pixels).
MarkerTexture PinTagTexture(int key, int square_px = 512);

/// Real photographs found on this machine (Debian packages), possibly empty.
const std::vector<std::string>& BackgroundPhotos();

}  // namespace pintag::scene
