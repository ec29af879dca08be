#pragma once
// The benchmark's deterministic sweep: which frames exist (size, tilt, photometry, pose, ids,
// background) and how each is turned into a scene for a given marker. Every frame is a pure
// function of its seed, so the three markers are rendered with the same pose on the same
// background with the same photometry and noise.

#include <cstdint>
#include <string>
#include <vector>

#include "pintag/scene/scene.hpp"

namespace pintag::bench {

/// Black-square sides in pixels, as the square would project facing the camera at its distance.
inline constexpr int kSizesPx[] = {160, 80, 48, 32, 24, 18, 14};
/// Viewing tilts, degrees (0 = facing the camera).
inline constexpr int kTiltsDeg[] = {0, 20, 40, 55, 65, 72, 78};
inline constexpr int kSizeCount = static_cast<int>(std::size(kSizesPx));
inline constexpr int kTiltCount = static_cast<int>(std::size(kTiltsDeg));
inline constexpr double kTagSideM = 0.05;  ///< every marker's black square, metres

/// The marker drawn in a frame.
enum class Marker { kPinTag, kAruco, kAprilTag };
inline constexpr int kMarkerCount = 3;
std::string ToString(Marker marker);

/// The camera of each world, all 1920 × 1080: the tuning world's f = 1400 px, the held-out
/// world's 1500 px (as phones' main cameras at 1080p), the blind world's 1650 px.
scene::Camera CameraFor(scene::World world);

/// The world's name in reports and on the command line: "tuning", "held-out" or "blind".
std::string ToString(scene::World world);

/// The held-out seed of pintag_bench's headline, its default. No tuning tool reads its frames.
inline constexpr std::uint64_t kHeadlineSeed = 1;

struct SweepOptions {
  scene::World world = scene::World::kHeldOut;
  int frames_per_bin = 8;   ///< frames per (size, tilt, photometry) bin
  int tagless_frames = 64;  ///< frames of photographs without a tag (moderate and hard alternate)
  /// One frame per (size, tilt), photometry alternating, and at most 6 tagless: CI's check and
  /// the load test's photos. Drawn from a seed of their own, so that they are none of the full
  /// sweep's frames (until 2026-12-07 they were its first round).
  bool quick = false;
  /// Base seed of the whole sweep. The held-out and blind worlds mix it with salts of their own,
  /// so no two worlds share a frame's seed.
  std::uint64_t seed = kHeadlineSeed;
  /// 0: every frame saved at the JPEG quality its light draws (the worlds' ranges); 1 … 100: every
  /// frame saved at this quality instead, the rest of its light unchanged (what a scanner app's
  /// upload quality costs).
  int jpeg_quality = 0;
  /// Held-out world only: save every frame's JPEG with full-resolution colour (4:4:4), not 4:2:0.
  bool jpeg_full_chroma = false;
  /// Held-out world only: a sensor whose every pixel senses all three colours, no colour filter
  /// array and no demosaic (what the mosaic at the output's resolution costs each detector).
  bool no_mosaic = false;
  /// Held-out world only: the phone senses and demosaics at this many times the output's
  /// resolution along each axis, then scales down (1: as the held-out phone does).
  int sensor_scale = 1;
  /// Tuning world only: give every frame's phone an S-shaped tone curve (Photometry::
  /// tone_contrast, drawn from the frame's seed: 0.1 … 0.6 in moderate light, 0.3 … 0.9 in hard),
  /// the rest of its light unchanged. The held-out phone always has one of its own.
  bool s_curve = false;
  /// Tuning world only: give every frame's phone a colour filter array, demosaiced by variable
  /// numbers of gradients (Photometry::vng_demosaic) rather than bilinearly, the rest of its light
  /// unchanged. An edge-directed demosaic of the tuning world's own, not the held-out phone's.
  bool vng_demosaic = false;
};

/// Empty when the options go together, else what is wrong, worded for the command line: each
/// world's own photometry options belong to it alone, and the blind world is run whole, as drawn.
std::string SweepOptionsError(const SweepOptions& options);

/// Empty when a tool that informs tuning (the reader and genie probes) may look at these frames,
/// else why not: the held-out world's headline seed and the whole blind world are read by
/// pintag_bench alone.
std::string TuningToolOptionsError(const SweepOptions& options);

struct FrameSpec {
  scene::World world = scene::World::kHeldOut;
  int index = 0;           ///< position in the sweep
  int size_index = -1;     ///< into kSizesPx; −1 on a tagless frame
  int tilt_index = -1;     ///< into kTiltsDeg; −1 on a tagless frame
  bool hard = false;       ///< Photometry::Hard, else Moderate
  std::uint64_t seed = 0;  ///< background, photometry and noise
  cv::Point2d centre;      ///< where the square's centre projects, px
  double tilt_axis_deg = 0;
  double roll_deg = 0;
  int pintag_key = 0;         ///< 0 … 32767
  int aruco_id = 0;           ///< 0 … 999 (DICT_5X5_1000)
  int apriltag_id = 0;        ///< 0 … 2319 (tag36h10)
  int background_photo = -1;  ///< tagless frames: the photograph, else chosen by the seed
  /// Held-out tagless frames: a label without a tag in view, its tag's place this many px (0:
  /// none) at this tilt (placed at `centre`, turned by the two angles above).
  int blank_label_px = 0;
  double blank_label_tilt_deg = 0;
  int jpeg_quality = 0;           ///< SweepOptions::jpeg_quality
  bool jpeg_full_chroma = false;  ///< SweepOptions::jpeg_full_chroma
  bool no_mosaic = false;         ///< SweepOptions::no_mosaic
  int sensor_scale = 1;           ///< SweepOptions::sensor_scale
  bool s_curve = false;           ///< SweepOptions::s_curve
  bool vng_demosaic = false;      ///< SweepOptions::vng_demosaic

  bool tagless() const { return size_index < 0; }
};

/// The frames of the sweep, tagged ones first, in a fixed order.
std::vector<FrameSpec> MakeSweep(const SweepOptions& options, const scene::Camera& camera);

/// The scene of `frame` carrying `marker` (ignored on tagless frames).
scene::SceneSpec SceneFor(const FrameSpec& frame, Marker marker, const scene::Camera& camera);

/// The truth id of `frame` for `marker`.
int TruthId(const FrameSpec& frame, Marker marker);

}  // namespace pintag::bench
