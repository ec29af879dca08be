#pragma once
// Everything that tunes the detector, in one struct. Every field states its default and unit;
// sizes are ratios of the image where that lets one set of options work at any resolution.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace pintag {

/// Pinhole camera in pixels of the (orientation-corrected) image, with OpenCV's distortion model.
struct CameraIntrinsics {
  double fx = 0;                   ///< focal length along x, px
  double fy = 0;                   ///< focal length along y, px
  double cx = 0;                   ///< principal point x, px
  double cy = 0;                   ///< principal point y, px
  std::vector<double> distortion;  ///< k1 k2 p1 p2 [k3 …] (OpenCV order); empty = none
};

/// Where the intrinsics used for pose came from.
enum class IntrinsicsSource : std::uint8_t {
  kGiven,    ///< DetectorOptions::intrinsics
  kExif,     ///< the photo's EXIF focal length
  kAssumed,  ///< DetectorOptions::assumed_hfov_deg: pose is approximate
};

/// The focal-length facts a photo's EXIF may carry (DESIGN.md §6 attribute names).
struct ExifCamera {
  std::optional<double> focal_length_35mm;         ///< Exif:FocalLengthIn35mmFilm, mm
  std::optional<double> focal_length_mm;           ///< Exif:FocalLength, mm
  std::optional<double> focal_plane_x_resolution;  ///< Exif:FocalPlaneXResolution, px per unit
  std::optional<int>
      focal_plane_resolution_unit;  ///< Exif:FocalPlaneResolutionUnit 2 in, 3 cm, 4 mm
};

struct DetectorOptions {
  // --- camera and tag ---
  std::optional<CameraIntrinsics>
      intrinsics;  ///< explicit intrinsics; default none (EXIF, else assumed)
  /// Field of view across the photo's longer side (a phone's, held level) when intrinsics are
  /// neither given nor in EXIF, degrees.
  double assumed_hfov_deg = 65;
  double tag_size_m = 0.050;  ///< side of the black square, metres (default 50 mm)

  // --- colour (CIELAB units, computed with integer stand-ins; see DESIGN.md §2) ---
  double red_min_a = 20;   ///< a pixel is red when a* >= this …
  double red_min_b = -30;  ///< … and b* >= this (keeps saturated blues, a* ~ +79, out)
  /// A second, fainter pass looks for tags the first did not decode: a* >= this, b* as above,
  /// blobs outside the tags already decoded and no larger than faint_max_element_area_px (the
  /// faint tags are the small ones; larger faint blobs are mostly warm photograph). Off when not
  /// below red_min_a.
  double faint_red_min_a = 12;
  double min_bit_span_b = 20;    ///< least b* difference between a tag's 1 and 0 levels
  double min_bit_margin = 0.30;  ///< |b* − mid| / half-span below this: the bit is read as unknown

  // --- sizes, relative to the image unless stated ---
  int min_element_area_px = 3;           ///< smallest red blob kept, pixels
  double max_element_area_ratio = 0.02;  ///< largest red blob, fraction of the image area
  /// Quad size scale N, pixels: a square needs area >= (N/2)^2 and shortest side >= 0.3 N (slack
  /// for steep views), so the smallest accepted side is well below N.
  int min_square_px = 20;
  int max_blobs = 4000;                ///< red blobs beyond this (by area) are ignored
  int faint_max_element_area_px = 60;  ///< largest red blob of the faint pass, pixels
  /// Blobs a cluster of the faint pass needs: 2 also tries pairs (on a small tag under a colour
  /// cast often only two red disks show any red); 3 as the main pass. Values below 2 count as 2.
  int faint_min_blobs = 2;
  /// Faint-pass clusters with more blobs than this are not searched: a tag gives 4, and ten or
  /// more faint blobs linked together are warm photograph (a region the size of the frame to
  /// threshold and trace, for no tag; see docs/DETECTOR.md). 0 = no limit.
  int faint_max_cluster_blobs = 9;
  /// Also look for tags by their dark square alone (small tags whose red disks blur, JPEG and a
  /// colour cast have washed below both red thresholds), outside the tags the red passes decoded.
  bool dark_square_candidates = true;

  // --- time ---
  /// Model reads per frame (stage 5b-5c, milliseconds each), for candidates the direct reader
  /// failed on. Spent in the order candidates come: the main red pass, its clusters with the most
  /// blobs first, then the faint pass, then dark squares. A winner's re-reads come out of the same
  /// reads (two on a narrow square; up to four through a Bayer mosaic when its lead is under 100
  /// independent samples, usually one); a winner they cannot be had for is refused. With
  /// threads > 1 which candidates of one pass get the last reads, and so whether such a winner is
  /// kept, depends on timing. 0 turns the model off.
  int max_model_reads = 16;

  // --- execution and diagnostics ---
  int threads = 1;        ///< worker threads for candidate tags; 1 = run in the caller's thread
  std::string debug_dir;  ///< when set, each stage writes an image here (debug only; slow),
                          ///< named as kDebugImageNames

  bool return_rejected = false;  ///< also report candidates that did not decode (key unset)
};

/// The files DetectorOptions::debug_dir receives, one per stage in pipeline order, replaced when
/// there: a caller keeps its photo and overlay out of their way.
inline constexpr std::array<const char*, 4> kDebugImageNames = {"1_redness.png", "2_blobs.png",
                                                                "3_quads.png", "4_detections.png"};

}  // namespace pintag
