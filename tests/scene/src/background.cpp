#include "background.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace pintag::scene {
namespace {

struct PhotoSource {
  const char* package;  ///< the Debian package that installs them (scripts/setup.sh test)
  const char* directory;
  std::vector<const char*> files;
};

// Colour photographs (and, held out, a few grey ones and a colour wheel). Several hold red and
// round things (fruit, sweets, a baboon's nose, a red cup, a motorcycle, a retina): the tagless
// scenes need them to show that the detector does not read tags into them. No two worlds share a
// photograph: nothing tuned on the first ever sees the others.
const std::vector<PhotoSource>& PhotoSources(World world) {
  static const std::vector<PhotoSource> tuning = {
      {"opencv-doc",
       "/usr/share/doc/opencv-doc/examples/data",
       {"fruits.jpg",     "apple.jpg",
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
  };
  static const std::vector<PhotoSource> held_out = {
      {"python3-skimage",
       "/usr/lib/python3/dist-packages/skimage/data",
       {"astronaut.png", "chelsea.png", "coffee.png", "motorcycle_left.png", "motorcycle_right.png",
        "rocket.jpg", "retina.jpg", "ihc.png", "brick.png", "grass.png", "gravel.png",
        "hubble_deep_field.jpg", "color.png", "coins.png", "camera.png"}},
      {"lomiri-wallpapers-20.04",
       "/usr/share/backgrounds",
       {"Kleiber_by_Lukas_Baubkus.jpg", "Infinite-Sea_by_Aury88.jpg"}},
  };
  // Photographs of another desktop's wallpapers, many of them red and green like the tag's
  // elements (a ladybird, a red marigold, an orange gerbera, leaves and grass).
  static const std::vector<PhotoSource> blind = {
      {"mate-backgrounds",
       "/usr/share/backgrounds/mate/nature",
       {"Aqua.jpg", "Blinds.jpg", "Dune.jpg", "FreshFlower.jpg", "Garden.jpg", "GreenMeadow.jpg",
        "LadyBird.jpg", "RainDrops.jpg", "Storm.jpg", "TwoWings.jpg", "Wood.jpg",
        "YellowFlower.jpg"}},
      {"mate-backgrounds", "/usr/share/backgrounds/mate/abstract", {"Elephants.jpg"}},
  };
  switch (world) {
    case World::kTuning:
      return tuning;
    case World::kHeldOut:
      return held_out;
    case World::kBlind:
      return blind;
  }
  return tuning;
}

// The fixed list, every file required: a missing photograph would silently change every frame.
std::vector<std::string> FindPhotos(World world) {
  std::vector<std::string> found;
  std::error_code error;
  for (const PhotoSource& source : PhotoSources(world)) {
    for (const char* file : source.files) {
      const std::filesystem::path path = std::filesystem::path(source.directory) / file;
      if (!std::filesystem::is_regular_file(path, error)) {
        throw std::runtime_error("scene: background photograph " + path.string() +
                                 " is missing; install the Debian package " + source.package +
                                 " (scripts/setup.sh test installs every package the tests need)");
      }
      found.push_back(path.string());
    }
  }
  return found;
}

/// Decoded photographs, loaded once per process. Large ones are reduced (area averaging) to at
/// most kMaxPhotoSide px: a crop of them fills a 1080p frame without aliasing.
constexpr int kMaxPhotoSide = 2400;
const cv::Mat& LoadPhoto(const std::string& path) {
  static std::mutex mutex;
  static std::map<std::string, cv::Mat> cache;
  const std::lock_guard lock(mutex);
  auto it = cache.find(path);
  if (it == cache.end()) {
    cv::Mat photo = cv::imread(path, cv::IMREAD_COLOR);
    if (photo.empty()) throw std::runtime_error("scene: cannot decode " + path);
    const int side = std::max(photo.cols, photo.rows);
    if (side > kMaxPhotoSide) {
      const double f = static_cast<double>(kMaxPhotoSide) / side;
      cv::resize(photo, photo, cv::Size(), f, f, cv::INTER_AREA);
    }
    it = cache.emplace(path, std::move(photo)).first;
  }
  return it->second;
}

cv::Scalar RandomColour(Rng& rng) {
  return cv::Scalar(rng.uniform(0, 255), rng.uniform(0, 255), rng.uniform(0, 255));
}

}  // namespace

const std::vector<std::string>& BackgroundPhotos(World world) {
  // Each list is looked for on first use only: tuning runs need nothing held out installed.
  switch (world) {
    case World::kTuning: {
      static const std::vector<std::string> tuning = FindPhotos(World::kTuning);
      return tuning;
    }
    case World::kHeldOut: {
      static const std::vector<std::string> held_out = FindPhotos(World::kHeldOut);
      return held_out;
    }
    case World::kBlind: {
      static const std::vector<std::string> blind = FindPhotos(World::kBlind);
      return blind;
    }
  }
  throw std::logic_error("scene: no such world");
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
/// scaled to `size` (bilinearly; `area_when_shrinking`: by area averaging where that shrinks it),
/// mirrored half the time.
cv::Mat CropPhoto(const cv::Mat& photo, cv::Size size, bool area_when_shrinking, Rng& rng) {
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
  const bool shrinking = cw > size.width;
  cv::Mat out;
  cv::resize(photo(cv::Rect(x0, y0, cw, ch)), out, size, 0, 0,
             area_when_shrinking && shrinking ? cv::INTER_AREA : cv::INTER_LINEAR);
  if (rng.chance(0.5)) cv::flip(out, out, 1);
  return out;
}

cv::Mat MakeBackground(const Camera& camera, World world, bool real, int photo, Rng& rng,
                       std::string& name) {
  const cv::Size size(camera.width, camera.height);
  const auto& photos = BackgroundPhotos(world);
  if (real) {
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
        // The tuning world keeps the frames it was tuned on (bilinear throughout).
        CropPhoto(source, cell.size(), DrawnAsPrinted(world), rng).copyTo(out(cell));
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
