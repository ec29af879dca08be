// RenderScene: background, markers far to near, then the camera's degradations.

#include <algorithm>
#include <numeric>
#include <opencv2/imgproc.hpp>

#include "background.hpp"
#include "composite.hpp"
#include "photometry.hpp"
#include "pintag/scene/rng.hpp"
#include "pintag/scene/scene.hpp"

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

int AutoSupersample(double square_px) {
  if (square_px <= 200) return 4;
  if (square_px <= 500) return 3;
  return 2;
}

}  // namespace

Scene RenderScene(const SceneSpec& spec) {
  const Camera& camera = spec.camera;
  Rng rng(spec.seed);
  Rng background_rng(rng.fork());
  Rng noise_rng(rng.fork());

  Scene scene;
  scene.bgr =
      detail::MakeBackground(camera, spec.real_background, background_rng, scene.background);

  // Far markers first, so that a nearer one covers them.
  std::vector<std::size_t> order(spec.markers.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return spec.markers[a].pose.translation[2] > spec.markers[b].pose.translation[2];
  });

  scene.truth.resize(spec.markers.size());
  for (const std::size_t index : order) {
    const PlacedMarker& marker = spec.markers[index];
    MarkerTruth& truth = scene.truth[index];
    truth.id = marker.id;
    truth.pose = marker.pose;
    truth.homography = SquareToImage(camera, marker.pose, marker.square_side_m);
    const double h = marker.square_side_m / 2;
    const cv::Vec3d model[4] = {{-h, -h, 0}, {h, -h, 0}, {h, h, 0}, {-h, h, 0}};
    bool in_front = true, in_frame = true;
    for (int i = 0; i < 4; ++i) {
      const cv::Vec3d p = marker.pose.rotation * model[i] + marker.pose.translation;
      in_front = in_front && p[2] > 0;
      truth.corners_px[i] = ProjectPoint(camera, marker.pose, model[i]);
      const cv::Point2d& c = truth.corners_px[i];
      in_frame = in_frame && c.x >= -0.5 && c.y >= -0.5 && c.x <= camera.width - 0.5 &&
                 c.y <= camera.height - 0.5;
    }
    for (int i = 0; i < 4; ++i) {
      truth.square_px += cv::norm(truth.corners_px[(i + 1) % 4] - truth.corners_px[i]) / 4;
    }
    truth.fully_visible = in_front && in_frame && marker.occluders.empty();
    if (!in_front || marker.texture.bgr.empty()) {
      truth.fully_visible = false;
      continue;
    }
    const int ss = spec.supersample > 0 ? spec.supersample : AutoSupersample(truth.square_px);
    const detail::LinearTexture texture = detail::PrepareTexture(marker.texture, marker.occluders);
    const bool drawn = detail::CompositeMarker(
        scene.bgr, texture, truth.homography * TextureToSquare(marker.texture), ss);
    if (!drawn) truth.fully_visible = false;
  }

  detail::ApplyPhotometry(scene.bgr, spec.photometry, noise_rng);
  return scene;
}

}  // namespace pintag::scene
