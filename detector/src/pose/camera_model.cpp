#include "pose/camera_model.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace pintag::stage {
namespace {

const double kFullFrameDiagonalMm = std::hypot(36.0, 24.0);  // 43.27 mm
// A 35 mm-equivalent focal length outside these is no lens a photo comes from (EXIF writers put
// 0 or 65535 for "unknown"): such a field is taken as absent.
constexpr double kMinEquivalentFocalMm = 2;
constexpr double kMaxEquivalentFocalMm = 2000;

std::optional<double> PixelsPerMm(double resolution, int unit) {
  if (!(resolution > 0)) return std::nullopt;
  switch (unit) {
    case 2:
      return resolution / 25.4;
    case 3:
      return resolution / 10.0;
    case 4:
      return resolution;
    default:
      return std::nullopt;
  }
}

}  // namespace

ResolvedCamera ResolveCamera(const DetectorOptions& options, const ExifCamera* exif, int width,
                             int height) {
  ResolvedCamera out;
  if (options.intrinsics && options.intrinsics->fx > 0 && options.intrinsics->fy > 0) {
    out.intrinsics = *options.intrinsics;
    out.source = IntrinsicsSource::kGiven;
    return out;
  }
  out.intrinsics.cx = (width - 1) / 2.0;
  out.intrinsics.cy = (height - 1) / 2.0;
  std::optional<double> focal_px;
  if (exif) {
    if (exif->focal_length_35mm && *exif->focal_length_35mm > 0) {
      focal_px = *exif->focal_length_35mm * std::hypot(width, height) / kFullFrameDiagonalMm;
    } else if (exif->focal_length_mm && *exif->focal_length_mm > 0 &&
               exif->focal_plane_x_resolution) {
      const auto per_mm = PixelsPerMm(*exif->focal_plane_x_resolution,
                                      exif->focal_plane_resolution_unit.value_or(2));
      if (per_mm) focal_px = *exif->focal_length_mm * *per_mm;
    }
  }
  const bool plausible =
      focal_px && std::isfinite(*focal_px) &&
      *focal_px * kFullFrameDiagonalMm / std::hypot(width, height) >= kMinEquivalentFocalMm &&
      *focal_px * kFullFrameDiagonalMm / std::hypot(width, height) <= kMaxEquivalentFocalMm;
  if (plausible) {
    out.source = IntrinsicsSource::kExif;
  } else {
    // Across the longer side: a portrait photo (EXIF-rotated upright) is the same lens turned, and
    // taking the field of view across its width halved every distance.
    const double fov = options.assumed_hfov_deg * std::numbers::pi / 180.0;
    focal_px = (std::max(width, height) / 2.0) / std::tan(fov / 2);
    out.source = IntrinsicsSource::kAssumed;
  }
  out.intrinsics.fx = out.intrinsics.fy = *focal_px;
  return out;
}

}  // namespace pintag::stage
