#include "label_photo.hpp"

#include <opencv2/imgcodecs.hpp>

#include "pintag/codec/label.hpp"

namespace pintag::serve_test {

Photo PhotographLabel(httplib::Client& client, const httplib::Headers& auth, const std::string& pin,
                      double tilt_deg, const scene::Camera& camera) {
  Photo photo;
  auto r = client.Get("/api/v1/labels/" + pin + ".png?dpi=300", auth);
  EXPECT_TRUE(r && r->status == 200);
  if (!r || r->status != 200) return photo;
  const std::vector<std::uint8_t> png(r->body.begin(), r->body.end());
  scene::MarkerTexture texture;
  texture.bgr = cv::imdecode(png, cv::IMREAD_COLOR);
  EXPECT_FALSE(texture.bgr.empty());
  // Where the renderer put the tag's black square on the label (exact in pixels).
  const LabelOptions options;  // 100 x 150 mm, 300 dpi: what the server rendered
  const LabelTagPixels at = TagPlacementPixels(options);
  const double x0 = at.square_x - 0.5, y0 = at.square_y - 0.5, n = at.square_side;
  texture.square_corners_px = {cv::Point2d{x0, y0}, cv::Point2d{x0 + n, y0},
                               cv::Point2d{x0 + n, y0 + n}, cv::Point2d{x0, y0 + n}};
  photo.square_mm = TagPlacement(options.size).square_side_mm;

  scene::SceneSpec spec;
  spec.camera = camera;
  spec.seed = 7;
  spec.photometry.noise_sigma = 2;
  spec.photometry.defocus_sigma_px = 0.5;
  scene::PlacedMarker marker;
  marker.texture = texture;
  marker.square_side_m = photo.square_mm / 1000;
  const double distance = scene::DistanceForSquarePx(spec.camera, 220, marker.square_side_m);
  // (900, 500) in the default 1920 x 1080 frame.
  const cv::Point2d centre{camera.width * 900.0 / 1920, camera.height * 500.0 / 1080};
  marker.pose = scene::MakePose(spec.camera, centre, distance, tilt_deg, 30, 20);
  spec.markers.push_back(marker);
  const scene::Scene rendered = scene::RenderScene(spec);
  photo.truth = rendered.truth.at(0);
  photo.camera = spec.camera;
  std::vector<std::uint8_t> jpeg;
  cv::imencode(".jpg", rendered.bgr, jpeg, {cv::IMWRITE_JPEG_QUALITY, 92});
  photo.jpeg.assign(jpeg.begin(), jpeg.end());
  return photo;
}

}  // namespace pintag::serve_test
