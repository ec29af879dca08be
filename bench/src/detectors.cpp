#include "detectors.hpp"

#include <apriltag/apriltag.h>
#include <apriltag/tag36h10.h>

#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "pintag/detector/detector.hpp"

// Under `valgrind --tool=callgrind --instr-atstart=no`, only PinTag's detect() is instrumented, so
// rendering runs at valgrind's base speed (docs/BENCHMARKS.md). Outside valgrind these are a few
// no-op instructions.
#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#define PINTAG_BENCH_PROFILE_BEGIN() CALLGRIND_START_INSTRUMENTATION
#define PINTAG_BENCH_PROFILE_END() CALLGRIND_STOP_INSTRUMENTATION
#else
#define PINTAG_BENCH_PROFILE_BEGIN()
#define PINTAG_BENCH_PROFILE_END()
#endif

namespace pintag::bench {
namespace {

// Pose of the square from its corners C0 … C3. SOLVEPNP_IPPE_SQUARE wants the model points in
// its own order (−s/2, s/2), (s/2, s/2), (s/2, −s/2), (−s/2, −s/2), i.e. our C3, C2, C1, C0.
void PoseFromCorners(const scene::Camera& camera, Found* found) {
  const double h = kTagSideM / 2;
  const std::vector<cv::Point3d> model{{-h, h, 0}, {h, h, 0}, {h, -h, 0}, {-h, -h, 0}};
  const std::vector<cv::Point2d> image{found->corners[3], found->corners[2], found->corners[1],
                                       found->corners[0]};
  cv::Vec3d rvec, tvec;
  if (!cv::solvePnP(model, image, cv::Mat(scene::CameraMatrix(camera)), cv::noArray(), rvec, tvec,
                    false, cv::SOLVEPNP_IPPE_SQUARE)) {
    return;
  }
  cv::Rodrigues(rvec, found->rotation);
  found->translation = tvec;
  found->has_pose = true;
}

class PinTagDetector final : public MarkerDetector {
 public:
  PinTagDetector(const scene::Camera& camera, DetectorOptions options, bool tuned,
                 ChromaUpsampling upsampling)
      : options_(std::move(options)), tuned_(tuned), upsampling_(upsampling) {
    options_.intrinsics = CameraIntrinsics{camera.fx, camera.fy, camera.cx, camera.cy, {}};
    options_.tag_size_m = kTagSideM;
    detector_ = Detector(options_);
  }
  std::string name() const override { return "PinTag"; }
  std::string description() const override {
    return std::string("pintag::Detector, ") +
           (tuned_ ? "options from --pintag-options" : "default options") +
           ", intrinsics given, 50 mm tag";
  }
  Marker marker() const override { return Marker::kPinTag; }
  void setThreads(int threads) override {
    options_.threads = threads;
    detector_ = Detector(options_);
  }
  std::vector<Found> detect(const cv::Mat& bgr) override {
    PINTAG_BENCH_PROFILE_BEGIN();
    const DetectResult result = detector_.detect(bgr, nullptr, upsampling_);
    PINTAG_BENCH_PROFILE_END();
    timings_ = result.timings;
    std::vector<Found> out;
    for (const Detection& d : result.detections) {
      if (!d.key) continue;
      Found f;
      f.id = d.key->value();
      for (int i = 0; i < 4; ++i) f.corners[i] = {d.corners[i].x, d.corners[i].y};
      if (d.pose.distance_m > 0) {
        f.has_pose = true;
        for (int r = 0; r < 3; ++r) {
          for (int c = 0; c < 3; ++c) f.rotation(r, c) = d.pose.rotation[r][c];
          f.translation[r] = d.pose.translation[r];
        }
      }
      out.push_back(f);
    }
    return out;
  }
  std::vector<std::pair<std::string, double>> lastStageTimes() const override {
    return {{"1 redness", timings_.redness_ms},
            {"2-3a blobs", timings_.blobs_ms},
            {"3b-4 quads", timings_.quads_ms},
            {"5a sample", timings_.sample_ms},
            {"5b model fit", timings_.model_fit_ms},
            {"5c codeword", timings_.codeword_ms},
            {"7 pose", timings_.pose_ms},
            {"total", timings_.total_ms}};
  }

 private:
  DetectorOptions options_;
  bool tuned_ = false;
  ChromaUpsampling upsampling_ = ChromaUpsampling::kBoth;
  Detector detector_;
  StageTimings timings_;
};

class ArucoDetector final : public MarkerDetector {
 public:
  explicit ArucoDetector(const scene::Camera& camera)
      : camera_(camera),
        dictionary_(cv::aruco::getPredefinedDictionary(cv::aruco::DICT_5X5_1000)),
        parameters_(cv::aruco::DetectorParameters::create()) {}
  std::string name() const override { return "ArUco"; }
  std::string description() const override {
    return "cv::aruco::detectMarkers (OpenCV " CV_VERSION
           " contrib), DICT_5X5_1000, default DetectorParameters";
  }
  Marker marker() const override { return Marker::kAruco; }
  void setThreads(int /*threads*/) override {}  // cv::setNumThreads
  std::vector<Found> detect(const cv::Mat& bgr) override {
    std::vector<std::vector<cv::Point2f>> corners;
    std::vector<int> ids;
    cv::aruco::detectMarkers(bgr, dictionary_, corners, ids, parameters_);
    std::vector<Found> out(ids.size());
    for (std::size_t i = 0; i < ids.size(); ++i) {
      out[i].id = ids[i];
      for (int k = 0; k < 4; ++k) out[i].corners[k] = corners[i][k];
      PoseFromCorners(camera_, &out[i]);
    }
    return out;
  }

 private:
  scene::Camera camera_;
  cv::Ptr<cv::aruco::Dictionary> dictionary_;
  cv::Ptr<cv::aruco::DetectorParameters> parameters_;
};

class AprilTagDetector final : public MarkerDetector {
 public:
  AprilTagDetector(const scene::Camera& camera, int decimate)
      : camera_(camera),
        decimate_(decimate),
        family_(tag36h10_create(), tag36h10_destroy),
        detector_(apriltag_detector_create(), apriltag_detector_destroy) {
    apriltag_detector_add_family(detector_.get(), family_.get());
    detector_->quad_decimate = static_cast<float>(decimate);
    detector_->nthreads = 1;
  }
  std::string name() const override { return "AprilTag d" + std::to_string(decimate_); }
  std::string description() const override {
    return "libapriltag tag36h10, quad_decimate " + std::to_string(decimate_) +
           ", other parameters at their defaults; time includes BGR->gray";
  }
  Marker marker() const override { return Marker::kAprilTag; }
  void setThreads(int threads) override { detector_->nthreads = threads; }
  std::vector<Found> detect(const cv::Mat& bgr) override {
    cv::cvtColor(bgr, gray_, cv::COLOR_BGR2GRAY);
    image_u8_t image{gray_.cols, gray_.rows, static_cast<int32_t>(gray_.step), gray_.data};
    zarray_t* detections = apriltag_detector_detect(detector_.get(), &image);
    std::vector<Found> out(static_cast<std::size_t>(zarray_size(detections)));
    for (int i = 0; i < zarray_size(detections); ++i) {
      apriltag_detection_t* d = nullptr;
      zarray_get(detections, i, &d);
      Found& f = out[static_cast<std::size_t>(i)];
      f.id = d->id;
      // libapriltag: p[0 … 3] are our C3, C2, C1, C0, with pixel centres at +0.5.
      for (int k = 0; k < 4; ++k) f.corners[k] = {d->p[3 - k][0] - 0.5, d->p[3 - k][1] - 0.5};
      PoseFromCorners(camera_, &f);
    }
    apriltag_detections_destroy(detections);
    return out;
  }

 private:
  scene::Camera camera_;
  int decimate_;
  std::unique_ptr<apriltag_family_t, void (*)(apriltag_family_t*)> family_;
  std::unique_ptr<apriltag_detector_t, void (*)(apriltag_detector_t*)> detector_;
  cv::Mat gray_;
};

}  // namespace

std::unique_ptr<MarkerDetector> MakePinTagDetector(const scene::Camera& camera,
                                                   const DetectorOptions& options, bool tuned,
                                                   ChromaUpsampling upsampling) {
  return std::make_unique<PinTagDetector>(camera, options, tuned, upsampling);
}
std::unique_ptr<MarkerDetector> MakeArucoDetector(const scene::Camera& camera) {
  return std::make_unique<ArucoDetector>(camera);
}
std::unique_ptr<MarkerDetector> MakeAprilTagDetector(const scene::Camera& camera, int decimate) {
  return std::make_unique<AprilTagDetector>(camera, decimate);
}

void GrayFloor(const cv::Mat& bgr, cv::Mat* gray) {
  cv::cvtColor(bgr, *gray, cv::COLOR_BGR2GRAY);
}

}  // namespace pintag::bench
