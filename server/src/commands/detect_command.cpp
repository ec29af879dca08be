// `pintag detect`: find every tag in a photo; print keys and poses (JSON with --json) and draw an
// overlay with outlines, keys and pose axes.

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <memory>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <vector>

#include "commands/commands.hpp"
#include "commands/option_checks.hpp"
#include "pintag/codec/file_output.hpp"
#include "pintag/codec/label.hpp"
#include "pintag/codec/mirror.hpp"
#include "pintag/detector/detector.hpp"
#include "pintag/detector/json.hpp"
#include "pintag/detector/tag_outline.hpp"

namespace pintag::cli {
namespace {

struct DetectArgs {
  std::string photo;
  // As /api/v1/detect: the tag printed on the default 100 x 150 mm label.
  double tag_size_mm = TagPlacement(kLabel100x150).square_side_mm;
  std::optional<double> fx, fy, cx, cy;
  std::vector<double> distortion;
  bool json = false;
  std::string overlay;
  std::string debug_dir;
  int threads = 1;
  std::int64_t max_pixels = kDefaultMaxPixels;
  bool rejected = false;
};

/// The shared outline (pintag/detector/tag_outline.hpp), plus what only the command draws: the pose
/// axes.
void DrawOverlay(cv::Mat image, const DetectResult& result, double tag_size_m) {
  const int thickness = OutlineThickness(image);
  const cv::Matx33d k(result.intrinsics.fx, 0, result.intrinsics.cx, 0, result.intrinsics.fy,
                      result.intrinsics.cy, 0, 0, 1);
  const cv::Mat dist = result.intrinsics.distortion.empty()
                           ? cv::Mat()
                           : cv::Mat(result.intrinsics.distortion, true).reshape(1, 1);
  for (const Detection& d : result.detections) {
    if (!d.key) {
      DrawTagOutline(image, d, cv::Scalar(0, 0, 255), {});
      continue;
    }
    char caption[64];
    std::snprintf(caption, sizeof caption, "%d  %.2f m", d.key->value(), d.pose.distance_m);
    DrawTagOutline(image, d, cv::Scalar(0, 255, 255), caption);
    // Pose axes from the square's centre: x (red) towards C1, y (green) towards C3, z (blue) out
    // of the tag towards the viewer.
    const double a = tag_size_m / 2;
    const std::vector<cv::Point3d> axes = {{0, 0, 0}, {a, 0, 0}, {0, a, 0}, {0, 0, -a}};
    std::vector<cv::Point2d> projected;
    const cv::Vec3d rvec(d.pose.rotation_vector.data()), tvec(d.pose.translation.data());
    cv::projectPoints(axes, rvec, tvec, k, dist, projected);
    const cv::Scalar colours[] = {{0, 0, 255}, {0, 200, 0}, {255, 64, 0}};
    for (int i = 0; i < 3; ++i) {
      cv::arrowedLine(image, projected[0], projected[i + 1], colours[i], thickness, cv::LINE_AA, 0,
                      0.15);
    }
  }
}

/// The overlay in the format its extension names, encoded in memory and written whole:
/// cv::imwrite does not check its file's close (WriteWholeFile).
void WriteOverlay(const std::string& path, const cv::Mat& image) {
  const std::string ext = std::filesystem::path(path).extension().string();
  std::vector<std::uint8_t> bytes;
  bool encoded = false;
  try {
    encoded = !ext.empty() && cv::imencode(ext, image, bytes);
  } catch (const cv::Exception&) {
    encoded = false;
  }
  if (!encoded) {
    throw std::runtime_error("cannot write overlay " + path + ": no image format for '" + ext +
                             "'");
  }
  const std::string failure = WriteWholeFile(
      path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
  if (!failure.empty()) throw std::runtime_error("cannot write overlay " + path + ": " + failure);
}

/// What the command line alone can tell is wrong, checked before the photo is read: a usage error
/// exits 2 whatever the photo (a missing one included). The intrinsics rules are the detect
/// route's (server/src/app/detect_route.cpp).
/// A detection's four corners as the text output prints them: "(x,y) (x,y) (x,y) (x,y)".
std::string CornersText(const Detection& d) {
  std::array<char, 160> text{};
  std::snprintf(text.data(), text.size(), "(%.1f,%.1f) (%.1f,%.1f) (%.1f,%.1f) (%.1f,%.1f)",
                d.corners[0].x, d.corners[0].y, d.corners[1].x, d.corners[1].y, d.corners[2].x,
                d.corners[2].y, d.corners[3].x, d.corners[3].y);
  return text.data();
}

/// Whether OpenCV writes an image named `path`: cv::haveImageWriter said yes for .exr, whose
/// encoder this build has switched off, so the overlay failed after the whole detection.
bool CanEncode(const std::string& path) {
  const std::string ext = std::filesystem::path(path).extension().string();
  if (ext.empty() || !cv::haveImageWriter(path)) return false;
  std::vector<std::uint8_t> bytes;
  try {
    return cv::imencode(ext, cv::Mat(2, 2, CV_8UC3, cv::Scalar(0, 0, 0)), bytes) && !bytes.empty();
  } catch (const cv::Exception&) {
    return false;
  }
}

/// Whether `path` names the file `given` names (`-`: the file on standard input): the same file
/// under another name or link, or, for a file not there yet, the same place.
bool SameFile(const std::string& given, const std::string& path) {
  namespace fs = std::filesystem;
  if (given == "-") {
    struct stat input {};
    struct stat other {};
    return ::fstat(STDIN_FILENO, &input) == 0 && ::stat(path.c_str(), &other) == 0 &&
           input.st_dev == other.st_dev && input.st_ino == other.st_ino;
  }
  std::error_code ec;
  if (fs::equivalent(given, path, ec)) return true;
  std::error_code a_error;
  std::error_code b_error;
  const fs::path a = fs::weakly_canonical(fs::absolute(given, a_error), a_error);
  const fs::path b = fs::weakly_canonical(fs::absolute(path, b_error), b_error);
  return !a_error && !b_error && a == b;
}

void CheckOptions(const DetectArgs& args) {
  const int given = args.fx.has_value() + args.fy.has_value();
  if (given == 1) throw UsageError("give both --fx and --fy, or neither");
  if ((args.cx || args.cy) && given != 2) throw UsageError("--cx and --cy need --fx and --fy");
  // OpenCV reads 4, 5, 8, 12 or 14 coefficients; with 6 or 7 its pose solver returns nothing.
  const std::size_t coefficients = args.distortion.size();
  if (coefficients != 0 && coefficients != 4 && coefficients != 5 && coefficients != 8) {
    throw UsageError("--distortion takes 4, 5 or 8 numbers (k1 k2 p1 p2 [k3 [k4 k5 k6]]), got " +
                     std::to_string(coefficients));
  }
  if (coefficients != 0 && given != 2) throw UsageError("--distortion needs --fx and --fy");
  if (!args.overlay.empty() && SameFile(args.photo, args.overlay)) {
    // `detect - --overlay photo.png < photo.png`: the photo is standard input's file.
    throw UsageError("--overlay " + args.overlay +
                     (args.photo == "-" ? " is the file on standard input, the photo itself"
                                        : " is the photo itself") +
                     "; give another file");
  }
  std::error_code ec;
  if (!args.overlay.empty()) {
    // Where the overlay cannot go is known now, not after the photo is read and searched.
    CheckFileToWrite("--overlay", args.overlay);
    if (!CanEncode(args.overlay)) {
      throw UsageError(
          "--overlay " + args.overlay +
          ": no image format for its extension; name a .png, .jpg, .webp or .tiff file");
    }
  }
  if (!args.debug_dir.empty() && std::filesystem::exists(args.debug_dir, ec) &&
      !std::filesystem::is_directory(args.debug_dir, ec)) {
    throw UsageError("--debug-dir " + args.debug_dir + " is not a directory");
  }
  // The stage images replace files of their names: the photo (`detect dd/4_detections.png
  // --debug-dir dd` overwrote it) and the overlay must not be among them.
  if (!args.debug_dir.empty()) {
    for (const char* name : kDebugImageNames) {
      const std::string stage = (std::filesystem::path(args.debug_dir) / name).string();
      if (SameFile(args.photo, stage)) {
        throw UsageError("--debug-dir " + args.debug_dir + " would write " + name +
                         " over the photo; give another directory");
      }
      if (!args.overlay.empty() && SameFile(args.overlay, stage)) {
        throw UsageError("--debug-dir " + args.debug_dir + " would write " + name +
                         " over the overlay " + args.overlay + "; give another directory");
      }
    }
  }
}

void Run(const DetectArgs& args) {
  CheckOptions(args);
  const LoadResult loaded = args.photo == "-"
                                ? LoadImageStream(std::cin, "standard input", args.max_pixels)
                                : LoadImageFile(args.photo, args.max_pixels);
  if (!loaded.image) throw std::runtime_error(loaded.error);
  // Made once the photo is read, so a photo that cannot be leaves no directory behind.
  if (!args.debug_dir.empty()) {
    // The detector writes its stage images without a word when it cannot: say so here instead.
    std::error_code ec;
    std::filesystem::create_directories(args.debug_dir, ec);
    if (ec) {
      throw std::runtime_error("cannot make --debug-dir " + args.debug_dir + ": " + ec.message());
    }
    if (::access(args.debug_dir.c_str(), W_OK | X_OK) != 0) {
      throw std::runtime_error("cannot write in --debug-dir " + args.debug_dir + ": " +
                               std::strerror(errno));
    }
  }

  DetectorOptions options;
  options.tag_size_m = args.tag_size_mm / 1000.0;
  options.threads = args.threads;
  options.debug_dir = args.debug_dir;
  options.return_rejected = args.rejected;
  if (args.fx && args.fy) {
    const cv::Mat& img = loaded.image->bgr;
    options.intrinsics =
        CameraIntrinsics{*args.fx, *args.fy, args.cx.value_or((img.cols - 1) / 2.0),
                         args.cy.value_or((img.rows - 1) / 2.0), args.distortion};
  }
  const DetectResult result = Detector(options).detect(*loaded.image);
  if (!result.error.empty()) throw std::runtime_error(result.error);

  if (args.json) {
    std::cout << ToJson(result).dump(2) << "\n";
  } else {
    const auto decoded = std::count_if(result.detections.begin(), result.detections.end(),
                                       [](const Detection& d) { return d.key.has_value(); });
    const auto rejected = static_cast<std::ptrdiff_t>(result.detections.size()) - decoded;
    std::cout << decoded << " tag(s)"
              << (args.rejected ? ", " + std::to_string(rejected) + " rejected candidate(s)" : "")
              << " in " << args.photo << " (" << loaded.image->bgr.cols << "x"
              << loaded.image->bgr.rows << ", intrinsics " << ToString(result.intrinsics_source)
              << ", " << result.timings.total_ms << " ms)\n";
    for (const PhotoWarning& w : result.warnings) std::cout << "  note: " << w.message << "\n";
    for (const Detection& d : result.detections) {
      if (!d.key) {
        std::printf("  rejected candidate  corners %s: %s\n", CornersText(d).c_str(),
                    d.reject_reason.c_str());
        continue;
      }
      std::printf("  key %5d  corners %s\n", d.key->value(), CornersText(d).c_str());
      std::printf(
          "             distance %.3f m  t = (%.3f, %.3f, %.3f) m  rvec = (%.3f, %.3f, "
          "%.3f)%s\n",
          d.pose.distance_m, d.pose.translation[0], d.pose.translation[1], d.pose.translation[2],
          d.pose.rotation_vector[0], d.pose.rotation_vector[1], d.pose.rotation_vector[2],
          d.pose_ambiguous ? "  (pose ambiguous)" : "");
      // The format has no handedness (docs/FORMAT.md, "Mirror images").
      if (const std::optional<TagKey> mirror = MirrorImageKey(*d.key);
          mirror && *mirror != *d.key) {
        std::printf("             in a mirrored photo this tag reads as key %d\n", mirror->value());
      }
    }
  }
  if (!args.overlay.empty()) {
    cv::Mat overlay = loaded.image->bgr.clone();
    DrawOverlay(overlay, result, options.tag_size_m);
    WriteOverlay(args.overlay, overlay);
  }
}

void AddDetectCommand(CLI::App& app) {
  auto args = std::make_shared<DetectArgs>();
  CLI::App* cmd = app.add_subcommand("detect", "Find, decode and pose every PinTag in a photo");
  cmd->add_option("photo", args->photo,
                  "JPEG, PNG, TIFF or WebP photo; - reads it from standard input")
      ->required();
  cmd->add_option("--tag-size-mm", args->tag_size_mm,
                  "side of the black square, millimetres (default: the tag of a 100x150mm label)")
      ->check(FiniteNumber())
      ->check(CLI::Range(1.0, 10000.0))
      ->capture_default_str();
  // The detect route's ranges (server/src/app/detect_route.cpp): beyond them a pose is NaN.
  cmd->add_option("--fx", args->fx, "focal length x, pixels (with --fy: intrinsics given)")
      ->check(NumberFromTo(1e-3, 1e7));
  cmd->add_option("--fy", args->fy, "focal length y, pixels")->check(NumberFromTo(1e-3, 1e7));
  cmd->add_option("--cx", args->cx,
                  "principal point x, pixels (default: image centre; needs --fx and --fy)")
      ->check(NumberFromTo(-1e6, 1e6));
  cmd->add_option("--cy", args->cy,
                  "principal point y, pixels (default: image centre; needs --fx and --fy)")
      ->check(NumberFromTo(-1e6, 1e6));
  cmd->add_option("--distortion", args->distortion,
                  "lens distortion in OpenCV's order: 4, 5 or 8 numbers (needs --fx and --fy)")
      // CLI11 would show "FLOAT x 4" (the least it takes): say which counts it reads instead.
      ->option_text("K1 K2 P1 P2 [K3 [K4 K5 K6]]")
      ->expected(4, 8)
      // Real lenses, fisheyes included, stay within units; 1e300 made every pose NaN.
      ->check(NumberFromTo(-1000, 1000));
  cmd->add_flag("--json", args->json, "print JSON");
  cmd->add_option("--overlay", args->overlay, "write the photo with outlines, keys and axes")
      ->check(FileName());
  cmd->add_option("--debug-dir", args->debug_dir, "write each pipeline stage's image here")
      ->check(FileName());
  cmd->add_flag("--rejected", args->rejected, "also list candidates that did not decode");
  cmd->add_option("--threads", args->threads, "worker threads")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  // As `serve --max-pixels`: past 1e9 a header's claim alone would make the loader ask for more
  // memory than the machine has.
  cmd->add_option("--max-pixels", args->max_pixels, "refuse larger images (at most 1e9)")
      ->check(CLI::Range(std::int64_t{1}, std::int64_t{1'000'000'000}))
      ->capture_default_str();
  cmd->callback([args] { Run(*args); });
}

const CommandRegistration detect_registration{"detect", &AddDetectCommand};

}  // namespace

}  // namespace pintag::cli
