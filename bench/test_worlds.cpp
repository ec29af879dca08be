// The benchmark's three worlds must stay apart: a photograph or a frame seed shared between them,
// or a tuning tool allowed to read the blind world, would let tuning see what judges it.
#include <gtest/gtest.h>

#include <filesystem>
#include <set>
#include <sstream>
#include <string>

#include "pintag/scene/scene.hpp"
#include "sweep.hpp"

namespace pintag::bench {
namespace {

constexpr scene::World kWorlds[] = {scene::World::kTuning, scene::World::kHeldOut,
                                    scene::World::kBlind};

TEST(Worlds, NoTwoWorldsShareAPhotographOrItsName) {
  std::set<std::string> paths, names;
  std::size_t total = 0;
  for (const scene::World world : kWorlds) {
    const std::vector<std::string>& photos = scene::BackgroundPhotos(world);
    EXPECT_GE(photos.size(), 12U) << ToString(world);
    for (const std::string& path : photos) {
      paths.insert(path);
      names.insert(std::filesystem::path(path).filename().string());
      ++total;
    }
  }
  EXPECT_EQ(paths.size(), total);
  EXPECT_EQ(names.size(), total);
}

TEST(Worlds, NoTwoWorldsShareAFrameSeedOrACamera) {
  std::set<std::uint64_t> seeds;
  std::set<double> focal_lengths;
  std::size_t total = 0;
  for (const scene::World world : kWorlds) {
    SweepOptions options;
    options.world = world;
    options.frames_per_bin = 1;
    options.tagless_frames = 8;
    const scene::Camera camera = CameraFor(world);
    focal_lengths.insert(camera.fx);
    for (const FrameSpec& frame : MakeSweep(options, camera)) {
      EXPECT_EQ(frame.world, world);
      seeds.insert(frame.seed);
      ++total;
    }
  }
  EXPECT_EQ(seeds.size(), total);
  EXPECT_EQ(focal_lengths.size(), std::size(kWorlds));
}

TEST(Worlds, TheBlindWorldTakesThePrintedPathOnItsOwnPhotographs) {
  SweepOptions options;
  options.world = scene::World::kBlind;
  options.frames_per_bin = 1;
  options.tagless_frames = 2;
  const scene::Camera camera = CameraFor(options.world);
  const std::vector<FrameSpec> frames = MakeSweep(options, camera);
  std::set<std::string> blind_names;
  for (const std::string& path : scene::BackgroundPhotos(scene::World::kBlind)) {
    blind_names.insert(std::filesystem::path(path).filename().string());
  }
  // A tagless frame of a printed world shows a label without its tag; a collage names its tiles
  // joined by '+'.
  const FrameSpec& tagless = frames.back();
  ASSERT_TRUE(tagless.tagless());
  EXPECT_GT(tagless.blank_label_px, 0);
  const scene::Scene scene = scene::RenderScene(SceneFor(tagless, Marker::kPinTag, camera));
  EXPECT_EQ(scene.bgr.size(), cv::Size(camera.width, camera.height));
  std::string name;
  std::stringstream tiles(scene.background);
  while (std::getline(tiles, name, '+')) EXPECT_TRUE(blind_names.count(name)) << name;
}

TEST(Worlds, TuningToolsMayNotReadTheBlindWorldAtAnySeed) {
  SweepOptions options;
  options.world = scene::World::kBlind;
  for (const std::uint64_t seed : {1ULL, 2ULL, 12345ULL}) {
    options.seed = seed;
    EXPECT_NE(TuningToolOptionsError(options).find("blind world"), std::string::npos);
  }
  options.world = scene::World::kHeldOut;
  options.seed = 2;
  EXPECT_EQ(TuningToolOptionsError(options), "");
  options.world = scene::World::kTuning;
  options.seed = kHeadlineSeed;
  EXPECT_EQ(TuningToolOptionsError(options), "");
}

TEST(Worlds, TheBlindWorldIsRunWholeAsDrawn) {
  SweepOptions options;
  options.world = scene::World::kBlind;
  EXPECT_EQ(SweepOptionsError(options), "");
  SweepOptions quick = options;
  quick.quick = true;
  EXPECT_NE(SweepOptionsError(quick).find("--quick"), std::string::npos);
  SweepOptions quality = options;
  quality.jpeg_quality = 90;
  EXPECT_NE(SweepOptionsError(quality).find("--jpeg-quality"), std::string::npos);
  // Every other world's photometry option, the held-out world's analyses included.
  SweepOptions full_chroma = options;
  full_chroma.jpeg_full_chroma = true;
  EXPECT_NE(SweepOptionsError(full_chroma), "");
  SweepOptions no_mosaic = options;
  no_mosaic.no_mosaic = true;
  EXPECT_NE(SweepOptionsError(no_mosaic), "");
  SweepOptions sensor = options;
  sensor.sensor_scale = 2;
  EXPECT_NE(SweepOptionsError(sensor), "");
  SweepOptions tone = options;
  tone.s_curve = true;
  EXPECT_NE(SweepOptionsError(tone), "");
  // The held-out world keeps its analyses.
  quality.world = scene::World::kHeldOut;
  EXPECT_EQ(SweepOptionsError(quality), "");
}

}  // namespace
}  // namespace pintag::bench
