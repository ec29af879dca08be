// Options and detections as JSON.

#include <gtest/gtest.h>

#include "pintag/detector/detector.hpp"
#include "pintag/detector/json.hpp"
#include "synthetic.hpp"

namespace pintag {
namespace {

TEST(Json, OptionsRoundTripAndRejectUnknownFields) {
  DetectorOptions o;
  o.tag_size_m = 0.08;
  o.threads = 2;
  o.dark_square_candidates = false;
  o.intrinsics = CameraIntrinsics{1000, 1001, 500, 400, {0.1, -0.2, 0, 0}};
  const nlohmann::json j = ToJson(o);
  DetectorOptions back;
  std::string error;
  ASSERT_TRUE(OptionsFromJson(j, &back, &error)) << error;
  EXPECT_EQ(back.tag_size_m, 0.08);
  EXPECT_EQ(back.threads, 2);
  EXPECT_FALSE(back.dark_square_candidates);
  ASSERT_TRUE(back.intrinsics);
  EXPECT_EQ(back.intrinsics->fy, 1001);
  EXPECT_EQ(ToJson(back), j);
  EXPECT_FALSE(OptionsFromJson({{"no_such_option", 1}}, &back, &error));
  EXPECT_FALSE(OptionsFromJson({{"threads", "two"}}, &back, &error));
  EXPECT_FALSE(OptionsFromJson(nlohmann::json::array(), &back, &error));
}

TEST(Json, DetectionCarriesKeyCornersPoseAndBits) {
  testing::SyntheticOptions s;
  const auto scene = testing::MakeScene({{.key = 4321, .square_px = 100, .tilt_deg = 30}}, s);
  const DetectResult r =
      Detector().detect(scene.bgr, nullptr, ChromaUpsampling::kNone);  // a render
  const nlohmann::json j = ToJson(r);
  ASSERT_EQ(j["detections"].size(), 1u);
  const nlohmann::json& d = j["detections"][0];
  EXPECT_EQ(d["key"], 4321);
  EXPECT_EQ(d["corners_px"].size(), 4u);
  EXPECT_EQ(d["pose"]["rotation_matrix"].size(), 3u);
  EXPECT_EQ(d["pose"]["quaternion_wxyz"].size(), 4u);
  EXPECT_TRUE(d["pose_ambiguous"].is_boolean());
  EXPECT_EQ(d["intrinsics"], "assumed");
  EXPECT_EQ(d["bits"]["green"].size(), 4u);
  EXPECT_EQ(j["intrinsics_source"], "assumed");
}

}  // namespace
}  // namespace pintag
