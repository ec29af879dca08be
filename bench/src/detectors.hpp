#pragma once
// The detectors under test behind one interface, each returning what a robot needs from a tag:
// id, the black square's corners (C0 … C3, pixel centres at integer coordinates, as the scene
// truth) and the pose of the square. Every call includes the pose, so the three produce the same
// output: PinTag's own pose; for ArUco and AprilTag cv::solvePnP with SOLVEPNP_IPPE_SQUARE.

#include <array>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "pintag/detector/chroma_upsampling.hpp"
#include "pintag/detector/options.hpp"
#include "pintag/scene/scene.hpp"
#include "sweep.hpp"

namespace pintag::bench {

struct Found {
  int id = -1;
  std::array<cv::Point2d, 4> corners{};
  bool has_pose = false;
  cv::Matx33d rotation = cv::Matx33d::eye();  ///< square model frame -> camera frame
  cv::Vec3d translation{0, 0, 0};             ///< square centre in the camera frame, metres
};

class MarkerDetector {
 public:
  virtual ~MarkerDetector() = default;
  /// Short name for tables, e.g. "AprilTag d2".
  virtual std::string name() const = 0;
  /// What it is, for the report, e.g. "libapriltag 3.3 tag36h10, quad_decimate 2, defaults".
  virtual std::string description() const = 0;
  /// The marker it looks for (whose rendering of a frame it gets).
  virtual Marker marker() const = 0;
  /// Worker threads for the next detect() calls. cv::setNumThreads is the caller's business.
  virtual void setThreads(int threads) = 0;
  virtual std::vector<Found> detect(const cv::Mat& bgr) = 0;
  /// Milliseconds per stage of the last detect() (PinTag only), in pipeline order.
  virtual std::vector<std::pair<std::string, double>> lastStageTimes() const { return {}; }
};

/// pintag::Detector with `options` (intrinsics and tag size are set here); `tuned` says in the
/// report that they are not the defaults. `upsampling`: how the frames' colour was decoded
/// (the sweep's 4:2:0 JPEGs unless --jpeg-chroma 444).
std::unique_ptr<MarkerDetector> MakePinTagDetector(
    const scene::Camera& camera, const DetectorOptions& options = {}, bool tuned = false,
    ChromaUpsampling upsampling = ChromaUpsampling::kBoth);
/// cv::aruco::detectMarkers, DICT_5X5_1000, default DetectorParameters (no corner refinement).
std::unique_ptr<MarkerDetector> MakeArucoDetector(const scene::Camera& camera);
/// libapriltag tag36h10 with its defaults except quad_decimate; includes the BGR->gray conversion
/// the library needs.
std::unique_ptr<MarkerDetector> MakeAprilTagDetector(const scene::Camera& camera, int decimate);

/// The floor: one pass over the pixels, cv::cvtColor BGR->GRAY.
void GrayFloor(const cv::Mat& bgr, cv::Mat* gray);

}  // namespace pintag::bench
