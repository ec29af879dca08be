#include "background.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace pintag::scene {
namespace {

struct PhotoSource {
  const char* directory;
  std::vector<const char*> files;
};

// Colour photographs only (no logos, drawings or grey calibration shots). Several hold red and
// round things (fruit, sweets, a baboon's nose, a red cup, a motorcycle): the tagless scenes
// need them to show that the detector does not read tags into them.
const std::vector<PhotoSource>& PhotoSources() {
  static const std::vector<PhotoSource> sources = {
      // Debian package opencv-doc: OpenCV's sample data.
      {"/usr/share/doc/opencv-doc/examples/data", {"fruits.jpg",     "apple.jpg",
                                                   "orange.jpg",     "smarties.png",
                                                   "baboon.jpg",     "butterfly.jpg",
                                                   "chicky_512.png", "rubberwhale1.png",
                                                   "messi5.jpg",     "building.jpg",
                                                   "home.jpg",       "aloeL.jpg",
                                                   "leuvenA.jpg",    "squirrel_cls.jpg",
                                                   "stuff.jpg",      "aero1.jpg",
                                                   "board.jpg",      "ela_original.jpg",
                                                   "pca_test1.jpg",  "graf1.png",
                                                   "cards.png",      "licenseplate_motion.jpg"}},
      // Debian package python3-skimage, where installed: scikit-image's sample data.
      {"/usr/lib/python3/dist-packages/skimage/data",
       {"astronaut.png", "chelsea.png", "coffee.png", "motorcycle_left.png", "rocket.jpg",
        "retina.jpg", "ihc.png", "brick.png", "grass.png", "gravel.png"}},
  };
  return sources;
}

std::vector<std::string> FindPhotos() {
  std::vector<std::string> found;
  std::error_code error;
  for (const PhotoSource& source : PhotoSources()) {
    for (const char* file : source.files) {
      const std::filesystem::path path = std::filesystem::path(source.directory) / file;
      if (std::filesystem::is_regular_file(path, error)) found.push_back(path.string());
    }
  }
  // Extra photographs (e.g. the team's own): every .jpg / .png in $PINTAG_SCENE_PHOTOS.
  if (const char* extra = std::getenv("PINTAG_SCENE_PHOTOS"); extra != nullptr && *extra) {
    std::vector<std::string> more;
    for (const auto& entry : std::filesystem::directory_iterator(extra, error)) {
      const std::string ext = entry.path().extension().string();
      if (ext == ".jpg" || ext == ".jpeg" || ext == ".png") more.push_back(entry.path().string());
    }
    std::sort(more.begin(), more.end());  // directory order is not stable
    found.insert(found.end(), more.begin(), more.end());
  }
  return found;
}

/// Decoded photographs, loaded once per process (they are small).
const cv::Mat& LoadPhoto(const std::string& path) {
  static std::mutex mutex;
  static std::map<std::string, cv::Mat> cache;
  const std::lock_guard lock(mutex);
  auto it = cache.find(path);
  if (it == cache.end()) it = cache.emplace(path, cv::imread(path, cv::IMREAD_COLOR)).first;
  return it->second;
}

cv::Scalar RandomColour(Rng& rng) {
  return cv::Scalar(rng.uniform(0, 255), rng.uniform(0, 255), rng.uniform(0, 255));
}

}  // namespace

const std::vector<std::string>& BackgroundPhotos() {
  static const std::vector<std::string> photos = FindPhotos();
  return photos;
}

namespace detail {

cv::Mat ProceduralBackground(cv::Size size, Rng& rng) {
  // Drawn at half resolution and scaled up: softer edges, like an out-of-focus backdrop, and fast.
  const cv::Size half((size.width + 1) / 2, (size.height + 1) / 2);
  cv::Mat canvas(half, CV_8UC3);
  const cv::Scalar top = RandomColour(rng), bottom = RandomColour(rng);
  for (int y = 0; y < half.height; ++y) {
    const double t = static_cast<double>(y) / std::max(1, half.height - 1);
    canvas.row(y).setTo(top * (1 - t) + bottom * t);
  }
  const int shapes = 20 + rng.below(40);
  const double scale = half.width / 960.0;
  for (int i = 0; i < shapes; ++i) {
    const cv::Point2f centre(static_cast<float>(rng.uniform(0, half.width)),
                             static_cast<float>(rng.uniform(0, half.height)));
    cv::Scalar colour = RandomColour(rng);
    switch (rng.below(5)) {
      case 0: {  // a box or sheet, at an angle
        const cv::RotatedRect box(centre,
                                  cv::Size2f(static_cast<float>(rng.uniform(20, 300) * scale),
                                             static_cast<float>(rng.uniform(20, 300) * scale)),
                                  static_cast<float>(rng.uniform(0, 180)));
        cv::Point2f p[4];
        box.points(p);
        const std::vector<cv::Point> poly = {p[0], p[1], p[2], p[3]};
        cv::fillConvexPoly(canvas, poly, colour, cv::LINE_AA);
        break;
      }
      case 1:  // red, orange or crimson disks: the hard negatives for a red-blob detector
        colour = rng.chance(0.5) ? cv::Scalar(rng.uniform(0, 60), rng.uniform(30, 110), 240)
                                 : cv::Scalar(rng.uniform(90, 140), rng.uniform(0, 40), 200);
        [[fallthrough]];
      case 2:
        cv::circle(canvas, centre, static_cast<int>(rng.uniform(4, 80) * scale) + 1, colour,
                   cv::FILLED, cv::LINE_AA);
        break;
      case 3:
        cv::ellipse(canvas,
                    cv::RotatedRect(centre,
                                    cv::Size2f(static_cast<float>(rng.uniform(10, 200) * scale),
                                               static_cast<float>(rng.uniform(10, 200) * scale)),
                                    static_cast<float>(rng.uniform(0, 180))),
                    colour, cv::FILLED, cv::LINE_AA);
        break;
      default: {
        const cv::Point2f end(static_cast<float>(centre.x + rng.uniform(-300, 300) * scale),
                              static_cast<float>(centre.y + rng.uniform(-300, 300) * scale));
        cv::line(canvas, centre, end, colour, 1 + rng.below(6), cv::LINE_AA);
        break;
      }
    }
  }
  cv::Mat out;
  cv::resize(canvas, out, size, 0, 0, cv::INTER_LINEAR);
  return out;
}

/// A random crop of `photo` with the aspect ratio of `size` (0.5 … 1 of the largest such crop),
/// scaled to `size`, mirrored half the time.
cv::Mat CropPhoto(const cv::Mat& photo, cv::Size size, Rng& rng) {
  const double aspect = static_cast<double>(size.width) / size.height;
  double w = photo.cols, h = photo.rows;
  if (w / h > aspect) {
    w = h * aspect;
  } else {
    h = w / aspect;
  }
  const double f = rng.uniform(0.5, 1.0);
  const int cw = std::max(2, static_cast<int>(w * f)), ch = std::max(2, static_cast<int>(h * f));
  const int x0 = rng.below(photo.cols - cw + 1), y0 = rng.below(photo.rows - ch + 1);
  cv::Mat out;
  cv::resize(photo(cv::Rect(x0, y0, cw, ch)), out, size, 0, 0, cv::INTER_LINEAR);
  if (rng.chance(0.5)) cv::flip(out, out, 1);
  return out;
}

cv::Mat MakeBackground(const Camera& camera, bool real, int photo, Rng& rng, std::string& name) {
  const cv::Size size(camera.width, camera.height);
  const auto& photos = BackgroundPhotos();
  if (real && !photos.empty()) {
    // The photographs are small (about 0.3 Mpx), so a whole 1080p frame of one is soft; a collage
    // of crops keeps more of their detail and packs more red, round things into a frame.
    int tiles = 1;
    if (photo < 0) {
      const double pick = rng.uniform();
      tiles = pick < 0.5 ? 1 : pick < 0.85 ? 2 : 3;
    }
    cv::Mat out(size, CV_8UC3);
    name.clear();
    for (int ty = 0; ty < tiles; ++ty) {
      for (int tx = 0; tx < tiles; ++tx) {
        const int index = photo >= 0 ? photo % static_cast<int>(photos.size())
                                     : rng.below(static_cast<int>(photos.size()));
        const cv::Mat& source = LoadPhoto(photos[index]);
        const cv::Rect cell(tx * size.width / tiles, ty * size.height / tiles,
                            (tx + 1) * size.width / tiles - tx * size.width / tiles,
                            (ty + 1) * size.height / tiles - ty * size.height / tiles);
        if (source.empty()) {
          out(cell).setTo(cv::Scalar(128, 128, 128));
          continue;
        }
        CropPhoto(source, cell.size(), rng).copyTo(out(cell));
        if (!name.empty()) name += '+';
        name += std::filesystem::path(photos[index]).filename().string();
      }
    }
    return out;
  }
  name = "procedural";
  return ProceduralBackground(size, rng);
}

}  // namespace detail
}  // namespace pintag::scene
