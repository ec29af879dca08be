#pragma once
// Intrinsics for pose: given ones, else from EXIF, else a default field of view (flagged).

#include "pintag/detector/options.hpp"

namespace pintag::stage {

struct ResolvedCamera {
  CameraIntrinsics intrinsics;
  IntrinsicsSource source = IntrinsicsSource::kAssumed;
};

/// `width` × `height`: the image as detected (EXIF orientation already applied).
///  - EXIF 35 mm equivalent f35: f = f35 × diagonal_px / 43.27 mm (the full-frame diagonal);
///  - EXIF focal length with focal-plane resolution: f = focal_mm × px_per_mm, the larger of the
///    pixel pitch's reading being the sensor's; the principal point is the image centre.
ResolvedCamera ResolveCamera(const DetectorOptions& options, const ExifCamera* exif, int width,
                             int height);

}  // namespace pintag::stage
