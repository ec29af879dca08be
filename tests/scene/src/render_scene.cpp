// RenderScene: background, markers far to near, then the camera's degradations.

#include <algorithm>
#include <array>
#include <numeric>
#include <opencv2/imgproc.hpp>

#include "background.hpp"
#include "composite.hpp"
#include "phone_capture.hpp"
#include "photometry.hpp"
#include "pintag/scene/rng.hpp"
#include "pintag/scene/scene.hpp"
#include "pyramid_warp.hpp"

namespace pintag::scene {
namespace {

/// Square units (x, y ∈ [0, 1], origin at C0) → image pixels: K [r1·s  r2·s  t − s/2 (r1 + r2)].
cv::Matx33d SquareToImage(const Camera& camera, const Pose& pose, double side_m) {
  const cv::Matx33d& r = pose.rotation;
  const cv::Vec3d r1(r(0, 0), r(1, 0), r(2, 0)), r2(r(0, 1), r(1, 1), r(2, 1));
  const cv::Vec3d c0 = pose.translation - 0.5 * side_m * (r1 + r2);
  const cv::Matx33d m(r1[0] * side_m, r2[0] * side_m, c0[0],  //
                      r1[1] * side_m, r2[1] * side_m, c0[1],  //
                      r1[2] * side_m, r2[2] * side_m, c0[2]);
  return CameraMatrix(camera) * m;
}

/// Texture pixels → square units, from the texture's square corners.
cv::Matx33d TextureToSquare(const MarkerTexture& texture) {
  std::vector<cv::Point2f> from, to = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (const cv::Point2d& p : texture.square_corners_px) from.emplace_back(p);
  const cv::Mat h = cv::getPerspectiveTransform(from, to, cv::DECOMP_LU);
  return cv::Matx33d(h);
}

/// Sub-samples per pixel side: 4 (17 coverage levels) for the sizes where sub-pixel accuracy
/// matters, fewer for large markers, whose area would make a 1080p frame slow.
int AutoSupersample(double square_px) {
  if (square_px <= 160) return 4;
  if (square_px <= 320) return 3;
  if (square_px <= 640) return 2;
  return 1;
}

/// Where the marker's whole texture (quiet zone included) lands in the image.
std::vector<cv::Point2f> TextureOutline(const MarkerTexture& texture,
                                        const cv::Matx33d& image_from_square) {
  const cv::Matx33d h = image_from_square * TextureToSquare(texture);
  const double w = texture.bgr.cols - 0.5, ht = texture.bgr.rows - 0.5;
  std::vector<cv::Point2f> outline;
  for (const cv::Point2d p :
       {cv::Point2d(-0.5, -0.5), cv::Point2d(w, -0.5), cv::Point2d(w, ht), cv::Point2d(-0.5, ht)}) {
    const cv::Vec3d q = h * cv::Vec3d(p.x, p.y, 1);
    outline.emplace_back(static_cast<float>(q[0] / q[2]), static_cast<float>(q[1] / q[2]));
  }
  return outline;
}

bool InFront(const PlacedMarker& marker) {
  const double h = marker.square_side_m / 2;
  for (const cv::Vec3d& m :
       {cv::Vec3d(-h, -h, 0), cv::Vec3d(h, -h, 0), cv::Vec3d(h, h, 0), cv::Vec3d(-h, h, 0)}) {
    if ((marker.pose.rotation * m + marker.pose.translation)[2] <= 0) return false;
  }
  return true;
}

/// Corners, size, homography; fully_visible from the frame and occluders only.
MarkerTruth MakeTruth(const Camera& camera, const PlacedMarker& marker) {
  MarkerTruth truth;
  truth.id = marker.id;
  truth.pose = marker.pose;
  truth.homography = SquareToImage(camera, marker.pose, marker.square_side_m);
  const double h = marker.square_side_m / 2;
  const cv::Vec3d model[4] = {{-h, -h, 0}, {h, -h, 0}, {h, h, 0}, {-h, h, 0}};
  bool in_frame = true;
  for (int i = 0; i < 4; ++i) {
    const cv::Point2d c = ProjectPoint(camera, marker.pose, model[i]);
    truth.corners_px[i] = c;
    in_frame = in_frame && c.x >= -0.5 && c.y >= -0.5 && c.x <= camera.width - 0.5 &&
               c.y <= camera.height - 0.5;
  }
  for (int i = 0; i < 4; ++i) {
    truth.square_px += cv::norm(truth.corners_px[(i + 1) % 4] - truth.corners_px[i]) / 4;
  }
  truth.fully_visible = in_frame && marker.occluders.empty();
  return truth;
}

}  // namespace

Scene RenderScene(const SceneSpec& spec) {
  const Camera& camera = spec.camera;
  Rng rng(spec.seed);
  Rng background_rng(rng.fork());
  Rng noise_rng(rng.fork());

  Scene scene;
  const bool printed = DrawnAsPrinted(spec.world);
  scene.bgr = detail::MakeBackground(camera, spec.world, spec.real_background,
                                     spec.background_photo, background_rng, scene.background);

  // Truth near to far, so that each marker is checked against the nearer ones' outlines; then
  // drawing far to near, so that a nearer marker covers a farther one.
  std::vector<std::size_t> order(spec.markers.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return spec.markers[a].pose.translation[2] < spec.markers[b].pose.translation[2];
  });
  scene.truth.resize(spec.markers.size());
  std::vector<std::vector<cv::Point2f>> nearer_outlines;
  std::vector<bool> drawable(spec.markers.size(), false);
  for (const std::size_t index : order) {
    const PlacedMarker& marker = spec.markers[index];
    MarkerTruth& truth = scene.truth[index];
    truth = MakeTruth(camera, marker);
    drawable[index] = InFront(marker) && !marker.texture.bgr.empty();
    if (!drawable[index]) {
      truth.fully_visible = false;
      continue;
    }
    const std::vector<cv::Point2f> square(truth.corners_px.begin(), truth.corners_px.end());
    for (const std::vector<cv::Point2f>& outline : nearer_outlines) {
      std::vector<cv::Point2f> overlap;
      if (cv::intersectConvexConvex(square, outline, overlap, true) > 0) {
        truth.fully_visible = false;
        break;
      }
    }
    nearer_outlines.push_back(TextureOutline(marker.texture, truth.homography));
  }
  for (auto it = order.rbegin(); it != order.rend(); ++it) {
    if (!drawable[*it]) continue;
    const PlacedMarker& marker = spec.markers[*it];
    MarkerTruth& truth = scene.truth[*it];
    const cv::Matx33d image_from_texture = truth.homography * TextureToSquare(marker.texture);
    bool drawn = false;
    if (printed) {
      const detail::PrintErrors print =
          detail::PrintErrors::Random(spec.print_seed ^ (0x9E37ULL * (*it + 1)));
      drawn = detail::WarpThroughPyramid(scene.bgr, marker.texture, image_from_texture, print);
    } else {
      const int ss = spec.supersample > 0 ? spec.supersample : AutoSupersample(truth.square_px);
      const detail::LinearTexture texture =
          detail::PrepareTexture(marker.texture, marker.occluders);
      drawn = detail::CompositeMarker(scene.bgr, texture, image_from_texture, ss);
    }
    if (!drawn) truth.fully_visible = false;  // part of the texture behind the camera
  }

  if (printed) {
    detail::ApplyPhoneCapture(scene.bgr, spec.capture, noise_rng);
  } else {
    detail::ApplyPhotometry(scene.bgr, spec.photometry, noise_rng);
  }
  return scene;
}

}  // namespace pintag::scene
