// Candidates found by their dark square alone (DetectorOptions::dark_square_candidates) on
// benchmark frames whose tag shows too little red for either red pass: rendered exactly as the
// sweep renders them, each is read with the right key with the dark-square pass and not at all
// without it.

#include <gtest/gtest.h>

#include <vector>

#include "detectors.hpp"
#include "pintag/scene/scene.hpp"
#include "sweep.hpp"

namespace pintag::bench {
namespace {

// Seed 1, 8 frames per bin: 32 px at 40° (hard), 32 px at 72° (moderate), 48 px at 65° (hard)
// and 24 px at 0° (hard).
const std::vector<int> kFrames = {72, 222, 361, 469};

TEST(DarkSquares, FindTagsWhoseRedNeitherRedPassSees) {
  const scene::Camera camera;
  const std::vector<FrameSpec> frames = MakeSweep(SweepOptions{}, camera);
  DetectorOptions without;
  without.dark_square_candidates = false;
  const std::unique_ptr<MarkerDetector> red_only = MakePinTagDetector(camera, without);
  const std::unique_ptr<MarkerDetector> detector = MakePinTagDetector(camera);
  for (int index : kFrames) {
    ASSERT_LT(index, static_cast<int>(frames.size()));
    const FrameSpec& frame = frames[static_cast<std::size_t>(index)];
    const scene::Scene rendered = scene::RenderScene(SceneFor(frame, Marker::kPinTag, camera));
    EXPECT_TRUE(red_only->detect(rendered.bgr).empty()) << "frame " << index;
    const std::vector<Found> found = detector->detect(rendered.bgr);
    ASSERT_EQ(found.size(), 1U) << "frame " << index;
    EXPECT_EQ(found[0].id, frame.pintag_key) << "frame " << index;
  }
}

}  // namespace
}  // namespace pintag::bench
