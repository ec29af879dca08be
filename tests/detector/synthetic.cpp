#include "synthetic.hpp"

#include <cmath>
#include <numbers>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "pintag/codec/cielab.hpp"
#include "pintag/codec/tag_raster.hpp"

namespace pintag::testing {
namespace {

constexpr double kTagSizeM = 0.05;

cv::Matx33d Rot(const cv::Vec3d& axis, double deg) {
  cv::Matx33d r;
  cv::Rodrigues(axis * (deg * std::numbers::pi / 180.0), r);
  return r;
}

cv::Mat Background(const SyntheticOptions& o, int s, std::mt19937_64& rng) {
  const int w = o.camera.width * s, h = o.camera.height * s;
  cv::Mat bg(h, w, CV_8UC3);
  std::uniform_int_distribution<int> u(40, 230);
  const cv::Scalar c0(u(rng), u(rng), u(rng)), c1(u(rng), u(rng), u(rng));
  for (int y = 0; y < h; ++y) {
    const double t = static_cast<double>(y) / h;
    bg.row(y).setTo(c0 * (1 - t) + c1 * t);
  }
  std::uniform_real_distribution<double> ux(0, w), uy(0, h), ur(5 * s, 60 * s);
  for (int i = 0; i < 25; ++i) {
    const cv::Scalar c(u(rng), u(rng), u(rng));
    cv::rectangle(bg, cv::Rect(ux(rng), uy(rng), ur(rng), ur(rng)), c, -1);
  }
  if (o.red_distractors) {
    const cv::Scalar reds[] = {{3, 80, 249}, {122, 13, 204}, {40, 40, 220}, {30, 60, 180}};
    for (int i = 0; i < 30; ++i) {
      const cv::Point p(ux(rng), uy(rng));
      const int r = static_cast<int>(ur(rng) / 4);
      cv::circle(bg, p, r, reds[i % 4], -1, cv::LINE_AA);
      if (i % 3 == 0) {  // red disk on a dark patch: the most tag-like distractor
        cv::rectangle(bg, cv::Rect(p.x - 3 * r, p.y - 3 * r, 6 * r, 6 * r), {25, 25, 25}, -1);
        cv::circle(bg, p, r, reds[i % 4], -1, cv::LINE_AA);
        cv::circle(bg, p + cv::Point(3 * r, 0), r, reds[(i + 1) % 4], -1, cv::LINE_AA);
      }
    }
  }
  return bg;
}

}  // namespace

SyntheticScene MakeScene(const std::vector<SyntheticTag>& tags, const SyntheticOptions& o) {
  std::mt19937_64 rng(o.seed);
  const int s = o.supersample;
  cv::Mat canvas = Background(o, s, rng);
  SyntheticScene scene;
  const cv::Matx33d k = o.camera.cameraMatrix();
  for (const SyntheticTag& tag : tags) {
    // Distance so that the square would be `square_px` wide frontally.
    const double z = o.camera.f * kTagSizeM / tag.square_px;
    const cv::Vec3d ray((tag.centre_px.x - k(0, 2)) / o.camera.f,
                        (tag.centre_px.y - k(1, 2)) / o.camera.f, 1);
    const cv::Vec3d t = ray * z;
    const double a = tag.tilt_axis_deg * std::numbers::pi / 180.0;
    const cv::Matx33d r =
        Rot({std::cos(a), std::sin(a), 0}, tag.tilt_deg) * Rot({0, 0, 1}, tag.roll_deg);
    // Tag units (u, v) -> camera: t + R ((u − 0.5) s, (v − 0.5) s, 0).
    const cv::Vec3d r1(r(0, 0), r(1, 0), r(2, 0)), r2(r(0, 1), r(1, 1), r(2, 1));
    const cv::Vec3d c0 = t - 0.5 * kTagSizeM * (r1 + r2);
    const cv::Matx33d m(r1[0] * kTagSizeM, r2[0] * kTagSizeM, c0[0], r1[1] * kTagSizeM,
                        r2[1] * kTagSizeM, c0[1], r1[2] * kTagSizeM, r2[2] * kTagSizeM, c0[2]);
    const cv::Matx33d tag_to_image = k * m;

    const int raster_px = 384;
    const TagRaster raster =
        RenderTagRaster(TagKey(static_cast<std::uint16_t>(tag.key)), {raster_px, 2});
    cv::Mat texture(raster.image.height, raster.image.width, CV_8UC3);
    for (int y = 0; y < texture.rows; ++y) {
      for (int x = 0; x < texture.cols; ++x) {
        const Rgb8 c = raster.image.at(x, y);
        texture.at<cv::Vec3b>(y, x) = {c.b, c.g, c.r};
      }
    }
    if (tag.occluded_element >= 0) {
      const double cu = tag.occluded_element == 0 || tag.occluded_element == 3 ? 0.25 : 0.75;
      const double cv_ = tag.occluded_element < 2 ? 0.25 : 0.75;
      cv::circle(texture,
                 cv::Point(static_cast<int>(raster.square_origin_px + cu * raster_px),
                           static_cast<int>(raster.square_origin_px + cv_ * raster_px)),
                 static_cast<int>(0.23 * raster_px), {150, 190, 225}, -1, cv::LINE_AA);
    }
    // Texture pixel centre x <-> tag unit u = (x + 0.5 − origin) / n.
    const double n = raster_px, o0 = raster.square_origin_px;
    const cv::Matx33d texture_to_tag(1 / n, 0, (0.5 - o0) / n, 0, 1 / n, (0.5 - o0) / n, 0, 0, 1);
    // Image pixel centre x <-> canvas pixel centre s (x + 0.5) − 0.5.
    const cv::Matx33d image_to_canvas(s, 0, 0.5 * s - 0.5, 0, s, 0.5 * s - 0.5, 0, 0, 1);
    const cv::Matx33d warp = image_to_canvas * tag_to_image * texture_to_tag;
    cv::warpPerspective(texture, canvas, cv::Mat(warp), canvas.size(), cv::INTER_LINEAR,
                        cv::BORDER_TRANSPARENT);

    SyntheticTruth truth;
    truth.key = tag.key;
    const double uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (int i = 0; i < 4; ++i) {
      const cv::Vec3d p = tag_to_image * cv::Vec3d(uv[i][0], uv[i][1], 1);
      truth.corners[i] = {p[0] / p[2], p[1] / p[2]};
    }
    truth.rotation = r;
    truth.translation = t;
    scene.truth.push_back(truth);
  }
  // Pixels integrate light, and optics blur it, in linear light; the tone curve comes last.
  cv::Mat lut(1, 256, CV_32F);
  for (int c = 0; c < 256; ++c) lut.at<float>(c) = static_cast<float>(SrgbToLinear(c));
  cv::Mat linear(canvas.size(), CV_32FC3);
  canvas.forEach<cv::Vec3b>([&](const cv::Vec3b& p, const int* pos) {
    linear.at<cv::Vec3f>(pos[0], pos[1]) = {lut.at<float>(p[0]), lut.at<float>(p[1]),
                                            lut.at<float>(p[2])};
  });
  cv::Mat small;
  cv::resize(linear, small, {o.camera.width, o.camera.height}, 0, 0, cv::INTER_AREA);
  if (o.blur_sigma > 0) cv::GaussianBlur(small, small, {0, 0}, o.blur_sigma);
  scene.bgr.create(small.size(), CV_8UC3);
  small.forEach<cv::Vec3f>([&](const cv::Vec3f& p, const int* pos) {
    scene.bgr.at<cv::Vec3b>(pos[0], pos[1]) = {LinearToSrgb(p[0]), LinearToSrgb(p[1]),
                                               LinearToSrgb(p[2])};
  });
  if (o.noise_sigma > 0) {
    cv::Mat noise(scene.bgr.size(), CV_16SC3);
    cv::theRNG().state = o.seed;
    cv::randn(noise, 0, o.noise_sigma);
    cv::Mat sum;
    scene.bgr.convertTo(sum, CV_16SC3);
    sum += noise;
    sum.convertTo(scene.bgr, CV_8UC3);
  }
  return scene;
}

}  // namespace pintag::testing
