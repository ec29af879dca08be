// The faint redness pass (DetectorOptions::faint_red_min_a) on benchmark frames whose tag no red
// pixel at a* >= 20 reveals well enough: rendered exactly as the sweep renders them, each is read
// with the right key with the pass and not at all without it. Likewise its pairs of blobs
// (faint_min_blobs = 2) on frames where only two red disks show any red.

#include <gtest/gtest.h>

#include <vector>

#include "detectors.hpp"
#include "pintag/scene/scene.hpp"
#include "sweep.hpp"

namespace pintag::bench {
namespace {

// Seed 1, 8 frames per bin: 32 px at 0° and 40° and 24 px at 20°, all hard photometry.
const std::vector<int> kFaintFrames = {266, 366, 470, 562};

std::vector<Found> DetectFrame(const FrameSpec& frame, const scene::Camera& camera,
                               const DetectorOptions& options) {
  const scene::Scene rendered = scene::RenderScene(SceneFor(frame, Marker::kPinTag, camera));
  return MakePinTagDetector(camera, options)->detect(rendered.bgr);
}

TEST(FaintPass, FindsSmallCastTagsTheMainPassMisses) {
  const scene::Camera camera;
  const std::vector<FrameSpec> frames = MakeSweep(SweepOptions{}, camera);
  // The faint pass alone: candidates found by their dark square (which also find some of these
  // tags) are off in both runs.
  DetectorOptions with;
  with.dark_square_candidates = false;
  DetectorOptions without = with;
  without.faint_red_min_a = without.red_min_a;  // off
  for (int index : kFaintFrames) {
    ASSERT_LT(index, static_cast<int>(frames.size()));
    const FrameSpec& frame = frames[static_cast<std::size_t>(index)];
    EXPECT_TRUE(DetectFrame(frame, camera, without).empty()) << "frame " << index;
    const std::vector<Found> found = DetectFrame(frame, camera, with);
    ASSERT_EQ(found.size(), 1U) << "frame " << index;
    EXPECT_EQ(found[0].id, frame.pintag_key) << "frame " << index;
  }
}

// Seed 1: 32 px at 20° (hard) and 32 px at 72° (moderate). At a* >= 12 each tag gives two red
// blobs of 3 px or more on its elements; the other disks show 2 px or nothing. (Frame 764, 24 px
// at 20° under hard light, was a third case; since the nearest-codeword rules of read_tag.hpp
// its pair's candidate no longer reads. The sweep still finds it, by its dark square.)
const std::vector<int> kPairFrames = {561, 712};

TEST(FaintPass, PairsOfBlobsFindTagsShowingOnlyTwoRedDisks) {
  const scene::Camera camera;
  const std::vector<FrameSpec> frames = MakeSweep(SweepOptions{}, camera);
  DetectorOptions pairs;
  pairs.dark_square_candidates = false;  // as above
  DetectorOptions triples = pairs;
  triples.faint_min_blobs = 3;
  for (int index : kPairFrames) {
    ASSERT_LT(index, static_cast<int>(frames.size()));
    const FrameSpec& frame = frames[static_cast<std::size_t>(index)];
    EXPECT_TRUE(DetectFrame(frame, camera, triples).empty()) << "frame " << index;
    const std::vector<Found> found = DetectFrame(frame, camera, pairs);
    ASSERT_EQ(found.size(), 1U) << "frame " << index;
    EXPECT_EQ(found[0].id, frame.pintag_key) << "frame " << index;
  }
}

}  // namespace
}  // namespace pintag::bench
