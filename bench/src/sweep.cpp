#include "sweep.hpp"

#include "pintag/codec/tag_key.hpp"
#include "pintag/scene/rng.hpp"

namespace pintag::bench {
namespace {

// Mixes the parts of a frame's identity into one seed (SplitMix64 finaliser over a running hash).
std::uint64_t Mix(std::uint64_t h, std::uint64_t v) {
  std::uint64_t z = h ^ (v + 0x9E3779B97F4A7C15ULL + (h << 6) + (h >> 2));
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

// The held-out world's salt: its frames' seeds are a stream the tuning world never draws from.
constexpr std::uint64_t kHeldOutSalt = 0x48454C444F5554ULL;
// The blind world's: a third stream.
constexpr std::uint64_t kBlindSalt = 0x424C494E44ULL;
constexpr std::uint64_t kQuickSalt = 0x515549434BULL;

FrameSpec TaggedFrame(std::uint64_t base, int round, bool hard, int size_index, int tilt_index,
                      const scene::Camera& camera) {
  FrameSpec f;
  f.size_index = size_index;
  f.tilt_index = tilt_index;
  f.hard = hard;
  std::uint64_t h = Mix(base, 0x7A66ED);
  for (std::uint64_t part :
       {static_cast<std::uint64_t>(round), std::uint64_t{hard},
        static_cast<std::uint64_t>(size_index), static_cast<std::uint64_t>(tilt_index)}) {
    h = Mix(h, part);
  }
  f.seed = h;
  scene::Rng rng(h);
  // The square with its quiet zone (1.3 sides), turned and seen in perspective, stays inside a
  // margin of 1.1 frontal sides around its centre.
  const double margin = 1.1 * kSizesPx[size_index] + 2;
  f.centre = {rng.uniform(margin, camera.width - margin),
              rng.uniform(margin, camera.height - margin)};
  f.tilt_axis_deg = rng.uniform(0, 360);
  f.roll_deg = rng.uniform(0, 360);
  f.pintag_key = rng.below(kKeyCount);
  f.aruco_id = rng.below(1000);
  f.apriltag_id = rng.below(2320);
  return f;
}

// The held-out and blind worlds draw from streams of their own; the tuning world's seeds are as
// given, so its frames stay those it was tuned on.
std::uint64_t WorldSeed(scene::World world, std::uint64_t seed) {
  switch (world) {
    case scene::World::kTuning:
      return seed;
    case scene::World::kHeldOut:
      return Mix(seed, kHeldOutSalt);
    case scene::World::kBlind:
      return Mix(seed, kBlindSalt);
  }
  return seed;
}

}  // namespace

scene::Camera CameraFor(scene::World world) {
  scene::Camera camera;
  switch (world) {
    case scene::World::kTuning:
      camera.fx = camera.fy = 1400;
      break;
    case scene::World::kHeldOut:
      camera.fx = camera.fy = 1500;
      break;
    case scene::World::kBlind:
      camera.fx = camera.fy = 1650;
      break;
  }
  return camera;
}

std::string ToString(scene::World world) {
  switch (world) {
    case scene::World::kTuning:
      return "tuning";
    case scene::World::kHeldOut:
      return "held-out";
    case scene::World::kBlind:
      return "blind";
  }
  return "?";
}

std::string SweepOptionsError(const SweepOptions& options) {
  if (options.world == scene::World::kBlind) {
    // Each look at the blind world by parts makes it less blind: it is run whole, as drawn (the
    // held-out world's analyses are refused below for every world but that one).
    if (options.quick)
      return "--quick is for the tuning and held-out worlds; the blind one is run whole";
    if (options.jpeg_quality != 0) {
      return "--jpeg-quality is an analysis of the held-out world; the blind world is run as drawn";
    }
  }
  if (options.s_curve && options.world != scene::World::kTuning) {
    return "--s-curve is for the tuning world (the held-out phone has its own)";
  }
  if (options.vng_demosaic && options.world != scene::World::kTuning) {
    return "--vng-demosaic is for the tuning world (the held-out phone has its own)";
  }
  if (options.jpeg_full_chroma && options.world != scene::World::kHeldOut) {
    return "--jpeg-chroma 444 is for the held-out world";
  }
  if (options.no_mosaic && options.world != scene::World::kHeldOut) {
    return "--no-mosaic is for the held-out world";
  }
  if (options.sensor_scale < 1 || options.sensor_scale > 4) return "--sensor-scale is 1 to 4";
  if (options.sensor_scale != 1 && options.world != scene::World::kHeldOut) {
    return "--sensor-scale is for the held-out world";
  }
  return {};
}

std::string TuningToolOptionsError(const SweepOptions& options) {
  if (options.world == scene::World::kBlind) {
    return "the blind world is read by pintag_bench's whole sweep alone, when an issue about the "
           "detector ends; a tool that informs tuning must not look at it";
  }
  if (options.world == scene::World::kHeldOut && options.seed == kHeadlineSeed) {
    return "the held-out world's seed " + std::to_string(kHeadlineSeed) +
           " is pintag_bench's headline, and a tool that informs tuning must not look at it: "
           "use --world tuning (the default), or another held-out seed with --seed";
  }
  return {};
}

std::string ToString(Marker marker) {
  switch (marker) {
    case Marker::kPinTag:
      return "PinTag";
    case Marker::kAruco:
      return "ArUco";
    case Marker::kAprilTag:
      return "AprilTag";
  }
  return "?";
}

std::vector<FrameSpec> MakeSweep(const SweepOptions& options, const scene::Camera& camera) {
  const bool printed = scene::DrawnAsPrinted(options.world);
  const std::uint64_t world_seed = WorldSeed(options.world, options.seed);
  const std::uint64_t seed = options.quick ? Mix(world_seed, kQuickSalt) : world_seed;
  std::vector<FrameSpec> frames;
  // Rounds outermost: any stretch of the sweep mixes every bin, so drift in the machine's load
  // spreads over all bins instead of landing on a few.
  if (options.quick) {
    for (int s = 0; s < kSizeCount; ++s) {
      for (int t = 0; t < kTiltCount; ++t) {
        frames.push_back(TaggedFrame(seed, 0, (s + t) % 2 == 1, s, t, camera));
      }
    }
  } else {
    for (int round = 0; round < options.frames_per_bin; ++round) {
      for (int hard = 0; hard < 2; ++hard) {
        for (int s = 0; s < kSizeCount; ++s) {
          for (int t = 0; t < kTiltCount; ++t) {
            frames.push_back(TaggedFrame(seed, round, hard == 1, s, t, camera));
          }
        }
      }
    }
  }
  const int tagless = options.quick ? std::min(options.tagless_frames, 6) : options.tagless_frames;
  const int photos = static_cast<int>(scene::BackgroundPhotos(options.world).size());
  for (int i = 0; i < tagless; ++i) {
    FrameSpec f;
    f.hard = i % 2 == 1;
    f.seed = Mix(Mix(seed, 0x7A6E55), static_cast<std::uint64_t>(i));
    f.background_photo = i % photos;
    if (printed) {
      // A label without its tag (text, border, the white place) in view, as on a parcel whose
      // tag is out of the frame: the detector must not read a tag into a label's print.
      scene::Rng rng(Mix(f.seed, 0xB1A4C));
      f.blank_label_px = kSizesPx[rng.below(kSizeCount)];
      const double margin = 1.1 * f.blank_label_px + 2;
      f.centre = {rng.uniform(margin, camera.width - margin),
                  rng.uniform(margin, camera.height - margin)};
      f.tilt_axis_deg = rng.uniform(0, 360);
      f.roll_deg = rng.uniform(0, 360);
      f.blank_label_tilt_deg = kTiltsDeg[rng.below(kTiltCount)];
    }
    frames.push_back(f);
  }
  for (std::size_t i = 0; i < frames.size(); ++i) {
    frames[i].index = static_cast<int>(i);
    frames[i].world = options.world;
    frames[i].jpeg_quality = options.jpeg_quality;
    frames[i].jpeg_full_chroma = options.jpeg_full_chroma;
    frames[i].no_mosaic = options.no_mosaic;
    frames[i].sensor_scale = options.sensor_scale;
    frames[i].s_curve = options.s_curve;
    frames[i].vng_demosaic = options.vng_demosaic;
  }
  return frames;
}

int TruthId(const FrameSpec& frame, Marker marker) {
  if (frame.tagless()) return -1;
  switch (marker) {
    case Marker::kPinTag:
      return frame.pintag_key;
    case Marker::kAruco:
      return frame.aruco_id;
    case Marker::kAprilTag:
      return frame.apriltag_id;
  }
  return -1;
}

scene::SceneSpec SceneFor(const FrameSpec& frame, Marker marker, const scene::Camera& camera) {
  scene::SceneSpec spec;
  spec.world = frame.world;
  spec.camera = camera;
  spec.seed = frame.seed;
  spec.print_seed = Mix(frame.seed, 0x9217);
  spec.real_background = true;
  spec.background_photo = frame.background_photo;
  spec.photometry =
      frame.hard ? scene::Photometry::Hard(frame.seed) : scene::Photometry::Moderate(frame.seed);
  spec.capture = frame.hard ? scene::PhoneCapture::Hard(frame.seed)
                            : scene::PhoneCapture::Moderate(frame.seed);
  if (frame.jpeg_quality > 0) {
    spec.photometry.jpeg_quality = frame.jpeg_quality;
    spec.capture.jpeg_quality = frame.jpeg_quality;
  }
  spec.capture.jpeg_full_chroma = frame.jpeg_full_chroma;
  spec.capture.mosaic = !frame.no_mosaic;
  spec.capture.sensor_scale = frame.sensor_scale;
  if (frame.s_curve) {
    scene::Rng rng(Mix(frame.seed, 0x5C0E));
    spec.photometry.tone_contrast = frame.hard ? rng.uniform(0.3, 0.9) : rng.uniform(0.1, 0.6);
  }
  if (frame.vng_demosaic) {
    spec.photometry.bayer = true;
    spec.photometry.vng_demosaic = true;
  }
  const bool printed = scene::DrawnAsPrinted(frame.world);
  if (frame.tagless() && frame.blank_label_px == 0) return spec;
  scene::PlacedMarker placed;
  placed.square_side_m = kTagSideM;
  if (frame.tagless()) {  // a blank label: not a marker, so no truth id
    placed.texture = scene::PrintedLabel(scene::LabelMarker::kNone, 0);
    placed.pose = scene::MakePose(
        camera, frame.centre, scene::DistanceForSquarePx(camera, frame.blank_label_px, kTagSideM),
        frame.blank_label_tilt_deg, frame.tilt_axis_deg, frame.roll_deg);
    spec.markers.push_back(std::move(placed));
    return spec;
  }
  placed.id = TruthId(frame, marker);
  switch (marker) {
    case Marker::kPinTag:
      placed.texture = printed ? scene::PrintedLabel(scene::LabelMarker::kPinTag, placed.id)
                               : scene::PinTagTexture(placed.id);
      break;
    case Marker::kAruco:
      placed.texture = printed ? scene::PrintedLabel(scene::LabelMarker::kAruco, placed.id)
                               : scene::ArucoTexture(placed.id);
      break;
    case Marker::kAprilTag:
      placed.texture = printed ? scene::PrintedLabel(scene::LabelMarker::kAprilTag, placed.id)
                               : scene::AprilTagTexture(placed.id);
      break;
  }
  placed.pose =
      scene::MakePose(camera, frame.centre,
                      scene::DistanceForSquarePx(camera, kSizesPx[frame.size_index], kTagSideM),
                      kTiltsDeg[frame.tilt_index], frame.tilt_axis_deg, frame.roll_deg);
  spec.markers.push_back(std::move(placed));
  return spec;
}

}  // namespace pintag::bench
