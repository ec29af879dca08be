#pragma once
// What the detector returns: plain values, no references into the image.

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "pintag/codec/cells.hpp"
#include "pintag/codec/tag_key.hpp"
#include "pintag/detector/options.hpp"

namespace pintag {

struct Point2 {
  double x = 0;
  double y = 0;
};

/// One planar pose solution: tag frame -> camera frame (x right, y down, z forward). The tag frame
/// has its origin at the square's centre, x towards C1, y towards C3, z into the tag.
struct PoseSolution {
  std::array<std::array<double, 3>, 3> rotation{};  ///< row-major rotation matrix
  std::array<double, 3> rotation_vector{};          ///< Rodrigues vector, radians
  std::array<double, 4> quaternion{};               ///< w, x, y, z (w >= 0)
  std::array<double, 3> translation{};              ///< square centre in the camera frame, metres
  double distance_m = 0;                            ///< |translation|, metres
  double reprojection_error_px = 0;                 ///< RMS over the four corners, pixels
};

/// Per-bit detail, in canonical orientation (element 0 is C0). margin = (b* − mid) / half-span:
/// positive reads 1, negative 0; |margin| < min_bit_margin (or a cell of the wrong colour) is
/// unknown.
struct BitMargins {
  std::array<std::array<double, kGreenSectors>, kElements> green{};
  std::array<std::array<double, kRedQuadrants>, kElements> red{};
};

struct Detection {
  std::optional<TagKey> key;                ///< set for every returned tag unless return_rejected
  std::string reject_reason;                ///< why key is unset (only with return_rejected)
  std::array<Point2, 4> corners{};          ///< black square corners C0 … C3, sub-pixel, px
  std::array<Point2, 4> element_centres{};  ///< element centres C0 … C3 through the homography, px
  std::array<bool, 4> element_seen{};       ///< whether a red blob was found at each element
  std::array<double, 9> homography{};       ///< row-major H: tag units (square = unit) -> pixels
  double square_px = 0;                     ///< mean side of the square in the image, px

  PoseSolution pose;              ///< the solution with the lower reprojection error
  PoseSolution alternative_pose;  ///< the other planar (IPPE) solution
  bool pose_ambiguous = false;    ///< the two solutions fit about equally well
  IntrinsicsSource intrinsics_source = IntrinsicsSource::kAssumed;

  CellReading cells;  ///< bits as read, canonical orientation
  BitMargins margins;
  int unknown_bits = 0;           ///< cells read as unknown
  int bits_from_second_copy = 0;  ///< payload bits taken from the other copy
  bool bit_from_parity = false;   ///< one code bit solved from the parity
  /// The cells were read by fitting a blur model to the pixels (the direct samples did not decode).
  bool read_through_blur_model = false;
  double min_known_margin = 0;  ///< smallest |margin| among bits that were read
};

/// Milliseconds spent per stage of DESIGN.md §3 in one detect() call (summed over worker threads
/// when DetectorOptions::threads > 1), and how many candidates the model reader read.
struct StageTimings {
  double redness_ms =
      0;                ///< 1: the frame scan (both redness levels, the half-resolution dark image)
  double blobs_ms = 0;  ///< 2-3a: red blobs, their rings, clusters of blobs
  double quads_ms = 0;  ///< 3b-4: quads, dark squares, corner refinement, element check
  double sample_ms = 0;     ///< 5a + 6 on direct samples: cells, orientation, payload, parity
  double model_fit_ms = 0;  ///< 5b: the model reader's fit (blur, corners, colours)
  double codeword_ms = 0;   ///< 5c + 6 for the model: the codeword decision and the codec's check
  double pose_ms = 0;       ///< 7
  double total_ms = 0;
  int model_reads = 0;     ///< candidates the model reader fitted
  int model_rereads = 0;   ///< more fits of narrow squares' winners, from moved corners
  int mosaic_rereads = 0;  ///< more fits of winners, through a Bayer mosaic of the detector's own
  int model_skipped = 0;   ///< candidates left because max_model_reads was spent (before their
                           ///< read or one of their re-reads)
};

/// Why a photo in which no tag was read could hold none, for the person holding the camera.
struct PhotoWarning {
  std::string code;     ///< stable, for programs: "no_colour"
  std::string message;  ///< for people: what is wrong and what to do
};

struct DetectResult {
  std::vector<Detection> detections;
  std::vector<PhotoWarning> warnings;  ///< only when no tag was read
  StageTimings timings;
  CameraIntrinsics intrinsics;  ///< what pose used
  IntrinsicsSource intrinsics_source = IntrinsicsSource::kAssumed;
  std::string error;  ///< non-empty when the input could not be processed
};

}  // namespace pintag
