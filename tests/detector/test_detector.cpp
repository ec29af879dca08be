// End to end on warp-based synthetic scenes: frontal, rotated, steep, small, several tags, one
// element covered, red clutter without tags.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "pintag/codec/mirror.hpp"
#include "pintag/detector/detector.hpp"
#include "synthetic.hpp"

namespace pintag {
namespace {

using testing::MakeScene;
using testing::SyntheticCamera;
using testing::SyntheticOptions;
using testing::SyntheticTag;

// The synthetic scenes are rendered straight to pixels: their colour was never subsampled.
constexpr ChromaUpsampling kRendered = ChromaUpsampling::kNone;

double MaxCornerError(const Detection& d, const testing::SyntheticTruth& t) {
  double worst = 0;
  for (int i = 0; i < 4; ++i) {
    worst = std::max(worst,
                     std::hypot(d.corners[i].x - t.corners[i].x, d.corners[i].y - t.corners[i].y));
  }
  return worst;
}

DetectorOptions OptionsFor(const SyntheticOptions& s) {
  DetectorOptions o;
  const SyntheticCamera& c = s.camera;  // the numbers of c.cameraMatrix()
  o.intrinsics = CameraIntrinsics{c.f, c.f, (c.width - 1) / 2.0, (c.height - 1) / 2.0, {}};
  // PINTAG_DEBUG_DIR=dir writes each stage's image and reports rejected candidates.
  if (const char* dir = std::getenv("PINTAG_DEBUG_DIR")) {
    o.debug_dir = dir;
    o.return_rejected = true;
  }
  return o;
}

TEST(Detector, FrontalTagAtEveryRoll) {
  for (double roll : {0.0, 33.0, 90.0, 180.0, 250.0}) {
    SyntheticOptions s;
    s.seed = static_cast<std::uint64_t>(roll) + 1;
    const auto scene = MakeScene({{.key = 12345, .square_px = 100, .roll_deg = roll}}, s);
    const DetectResult r = Detector(OptionsFor(s)).detect(scene.bgr, nullptr, kRendered);
    ASSERT_EQ(r.detections.size(), 1u) << "roll " << roll;
    const Detection& d = r.detections[0];
    ASSERT_TRUE(d.key);
    EXPECT_EQ(d.key->value(), 12345);
    EXPECT_LT(MaxCornerError(d, scene.truth[0]), 0.5) << "roll " << roll;
    EXPECT_EQ(d.unknown_bits, 0);
    EXPECT_EQ(r.intrinsics_source, IntrinsicsSource::kGiven);
  }
}

TEST(Detector, AMirroredTagReadsAsItsMirrorImageKeyOrAsNothing) {
  // The format has no handedness (docs/FORMAT.md, "Mirror images"): a flipped photo of key 55
  // shows key 109's tag exactly. What the codec says a mirror shows is what the detector reads.
  int mirrored_keys = 0;
  for (const int key : {55, 109, 12345, 20000, 7, 31000}) {
    SyntheticOptions s;
    s.seed = static_cast<std::uint64_t>(key) + 3;
    const auto scene = MakeScene({{.key = key, .square_px = 100, .roll_deg = 20.0}}, s);
    cv::Mat flipped;
    cv::flip(scene.bgr, flipped, 1);
    const DetectResult r = Detector(OptionsFor(s)).detect(flipped, nullptr, kRendered);
    std::vector<int> read;
    for (const Detection& d : r.detections) {
      if (d.key) read.push_back(d.key->value());
    }
    if (const std::optional<TagKey> mirror = MirrorImageKey(TagKey(key))) {
      ++mirrored_keys;
      EXPECT_EQ(read, std::vector<int>{mirror->value()}) << "key " << key;
    } else {
      EXPECT_TRUE(read.empty()) << "key " << key << " mirrored read as " << read.front();
    }
  }
  EXPECT_GE(mirrored_keys, 2);  // 55 and 109, a pair
}

TEST(Detector, SteepSeventyDegreesAtFortyEightPixels) {
  int found = 0, total = 0;
  for (double axis : {0.0, 45.0, 90.0, 160.0}) {
    SyntheticOptions s;
    s.seed = static_cast<std::uint64_t>(axis) + 11;
    const auto scene = MakeScene(
        {{.key = 777, .square_px = 72, .tilt_deg = 70, .tilt_axis_deg = axis, .roll_deg = 20}}, s);
    const DetectResult r = Detector(OptionsFor(s)).detect(scene.bgr, nullptr, kRendered);
    ++total;
    for (const Detection& d : r.detections) {
      ASSERT_TRUE(d.key);
      EXPECT_EQ(d.key->value(), 777);
      ++found;
    }
  }
  EXPECT_EQ(found, total);
}

TEST(Detector, SeveralTagsAtDifferentSizesAndRotations) {
  SyntheticOptions s;
  s.seed = 5;
  const std::vector<SyntheticTag> tags = {
      {.key = 1, .centre_px = {150, 150}, .square_px = 90, .roll_deg = 10},
      {.key = 32767, .centre_px = {450, 140}, .square_px = 60, .tilt_deg = 40, .roll_deg = 200},
      {.key = 20000,
       .centre_px = {760, 300},
       .square_px = 160,
       .tilt_deg = 25,
       .tilt_axis_deg = 80,
       .roll_deg = -70},
      {.key = 4242, .centre_px = {250, 420}, .square_px = 70, .tilt_deg = 55, .roll_deg = 120},
  };
  const auto scene = MakeScene(tags, s);
  const DetectResult r = Detector(OptionsFor(s)).detect(scene.bgr, nullptr, kRendered);
  ASSERT_EQ(r.detections.size(), tags.size());
  for (const SyntheticTag& t : tags) {
    bool seen = false;
    for (const Detection& d : r.detections) seen |= d.key && d.key->value() == t.key;
    EXPECT_TRUE(seen) << t.key;
  }
}

TEST(Detector, OneElementCoveredStillDecodesWithPose) {
  for (int element = 0; element < 4; ++element) {
    SyntheticOptions s;
    s.seed = 40 + element;
    const auto scene = MakeScene({{.key = 31000,
                                   .square_px = 110,
                                   .tilt_deg = 30,
                                   .roll_deg = 15.0 * element,
                                   .occluded_element = element}},
                                 s);
    const DetectResult r = Detector(OptionsFor(s)).detect(scene.bgr, nullptr, kRendered);
    ASSERT_EQ(r.detections.size(), 1u) << "element " << element;
    const Detection& d = r.detections[0];
    ASSERT_TRUE(d.key) << d.reject_reason;
    EXPECT_EQ(d.key->value(), 31000);
    EXPECT_FALSE(d.element_seen[element]);
    EXPECT_GT(d.bits_from_second_copy, 0);
    EXPECT_GT(d.pose.distance_m, 0);
    const cv::Vec3d t = scene.truth[0].translation;
    EXPECT_NEAR(d.pose.translation[2], t[2], 0.02 * cv::norm(t));
  }
}

TEST(Detector, RedClutterWithoutTagsGivesNothing) {
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    SyntheticOptions s;
    s.seed = seed;
    s.red_distractors = true;
    s.noise_sigma = 3;
    const auto scene = MakeScene({}, s);
    EXPECT_TRUE(Detector(OptionsFor(s)).detect(scene.bgr, nullptr, kRendered).detections.empty())
        << seed;
  }
}

TEST(Detector, BlurAndNoise) {
  SyntheticOptions s;
  s.seed = 9;
  s.blur_sigma = 1.0;
  s.noise_sigma = 4;
  const auto scene = MakeScene({{.key = 9999, .square_px = 80, .tilt_deg = 35, .roll_deg = 60}}, s);
  const DetectResult r = Detector(OptionsFor(s)).detect(scene.bgr, nullptr, kRendered);
  ASSERT_EQ(r.detections.size(), 1u);
  EXPECT_EQ(r.detections[0].key->value(), 9999);
}

TEST(Detector, RejectsBadImagesAsValues) {
  const Detector detector;
  EXPECT_FALSE(detector.detect(cv::Mat()).error.empty());
  EXPECT_FALSE(detector.detect(cv::Mat(10, 10, CV_8UC1, cv::Scalar(0))).error.empty());
  EXPECT_TRUE(detector.detect(cv::Mat(1, 1, CV_8UC3, cv::Scalar(0, 0, 255))).detections.empty());
  EXPECT_TRUE(
      detector.detect(cv::Mat(1, 100000, CV_8UC3, cv::Scalar(0, 0, 255))).detections.empty());
  EXPECT_TRUE(
      detector.detect(cv::Mat(100000, 1, CV_8UC3, cv::Scalar(0, 0, 255))).detections.empty());
}

TEST(Detector, ThreadsGiveTheSameAnswer) {
  SyntheticOptions s;
  const auto scene =
      MakeScene({{.key = 5, .centre_px = {200, 200}}, {.key = 6, .centre_px = {700, 300}}}, s);
  DetectorOptions o = OptionsFor(s);
  const auto one = Detector(o).detect(scene.bgr, nullptr, kRendered);
  o.threads = 2;
  const auto two = Detector(o).detect(scene.bgr, nullptr, kRendered);
  ASSERT_EQ(one.detections.size(), 2u);
  ASSERT_EQ(two.detections.size(), 2u);
  // The same tags with the same corners and pose, in whatever order the threads finished.
  const auto by_key = [](std::vector<Detection> d) {
    std::sort(d.begin(), d.end(),
              [](const Detection& a, const Detection& b) { return a.key < b.key; });
    return d;
  };
  const std::vector<Detection> a = by_key(one.detections), b = by_key(two.detections);
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_TRUE(a[i].key.has_value());
    EXPECT_EQ(a[i].key, b[i].key);
    for (std::size_t c = 0; c < 4; ++c) {
      EXPECT_NEAR(a[i].corners[c].x, b[i].corners[c].x, 1e-9);
      EXPECT_NEAR(a[i].corners[c].y, b[i].corners[c].y, 1e-9);
    }
    for (std::size_t t = 0; t < 3; ++t) {
      EXPECT_NEAR(a[i].pose.translation[t], b[i].pose.translation[t], 1e-9);
      EXPECT_NEAR(a[i].pose.rotation_vector[t], b[i].pose.rotation_vector[t], 1e-9);
    }
  }
}

}  // namespace
}  // namespace pintag
