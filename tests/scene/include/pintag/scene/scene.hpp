#pragma once
// Synthetic camera scenes with ground truth, for detector tests and the benchmark.
//
// A marker texture (a PinTag from the real renderer, or an ArUco / AprilTag marker) is placed with
// a known pose in front of a known pinhole camera, over a background (a real photograph from a
// fixed list installed by Debian packages, or procedural clutter), then degraded.
//
// Two worlds, two rendering paths (World). Tuning scenes: supersampled anti-aliasing in linear
// light, lighting gradient, colour cast, defocus and motion blur, sensor noise, Bayer
// demosaicing, JPEG. Held-out scenes, which no tuning run looks at: the marker printed on a label,
// warped through an image pyramid in sRGB, then a phone's pipeline (PhoneCapture). Everything is
// deterministic for a given seed (same binary; a missing photograph is an error, never a silent
// change of frames): the random numbers come from pintag/scene/rng.hpp, not from std::
// distributions. All functions are safe to call from several threads at once.

#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

namespace pintag::scene {

/// Pinhole camera without distortion, pixels. Pixel centres are at integer coordinates (as in
/// OpenCV): the top-left pixel covers [−0.5, 0.5]².
struct Camera {
  double fx = 1400, fy = 1400, cx = 960, cy = 540;
  int width = 1920, height = 1080;
};

/// The 3×3 intrinsic matrix K of `camera`.
cv::Matx33d CameraMatrix(const Camera& camera);

/// A marker image and where its black square (the part whose side is `square_side_m`) lies in it:
/// the square's four corners in texture pixels, C0 top-left then clockwise. The rest of the
/// texture (quiet zone) is drawn too.
/// Texture coordinates follow the same convention as images: pixel centres at integers, so a
/// square spanning pixels [o, o + n) has its outer corners at o − 0.5 and o + n − 0.5.
struct MarkerTexture {
  cv::Mat bgr;  ///< CV_8UC3
  std::array<cv::Point2d, 4> square_corners_px;
};

/// Pose of the marker's square in the camera frame: x right, y down, z forward (OpenCV
/// convention). The square's model points are (±s/2, ±s/2, 0) with C0 = (−s/2, −s/2, 0).
struct Pose {
  cv::Matx33d rotation = cv::Matx33d::eye();
  cv::Vec3d translation{0, 0, 1};
};

/// Pose from viewing parameters: distance (m) of the square's centre along the ray through
/// image point `centre_px`, tilt (degrees, 0 = facing the camera) about an axis in the square's
/// plane at `tilt_axis_deg`, and in-plane rotation `roll_deg`.
/// Tilt 0 means the square's normal points along that ray (a frontal view, wherever in the frame
/// the square is); the tilt axis is measured in the image, 0° = image x axis, clockwise (towards
/// +y); roll turns the square about its own normal, clockwise as seen by the camera.
Pose MakePose(const Camera& camera, cv::Point2d centre_px, double distance_m, double tilt_deg,
              double tilt_axis_deg, double roll_deg);

/// Distance (m) at which a frontal square of side `side_m` at the principal point spans
/// `square_px` pixels: fx · side / square_px. (Off-axis and tilted squares project differently;
/// MarkerTruth::square_px has what was rendered.)
double DistanceForSquarePx(const Camera& camera, double square_px, double side_m = 0.05);

/// Viewing angle in degrees between the square's normal and the ray to its centre (0 = frontal).
double ViewTiltDeg(const Pose& pose);

/// Projects a point given in the square's model frame (metres) to image pixels.
cv::Point2d ProjectPoint(const Camera& camera, const Pose& pose, const cv::Vec3d& model_point_m);

/// Which side of the benchmark a scene belongs to. Detector work is tuned on kTuning scenes only;
/// kHeldOut scenes check it on what it never saw: other photographs, and a second rendering path
/// (a printed label warped through an image pyramid with area averaging in sRGB, then a phone's
/// pipeline: see PhoneCapture). kBlind is held out a second time: the held-out world's rendering
/// path and phone, on photographs, a camera and seeds of its own, and read by pintag_bench's whole
/// sweep alone, when an issue about the detector ends. The held-out world has been a validation set
/// (changes kept by its result); the blind world is what no decision has looked at.
enum class World { kTuning, kHeldOut, kBlind };

/// Whether the world's scenes take the second rendering path (the printed label through a pyramid,
/// then PhoneCapture) rather than the tuning world's texture warp and Photometry.
constexpr bool DrawnAsPrinted(World world) {
  return world != World::kTuning;
}

enum class Cast { kNone, kTungsten, kFluorescent, kShade };

struct Photometry {
  double gradient = 0;  ///< brightness falloff across the frame, 0 … 0.6
  Cast cast = Cast::kNone;
  double defocus_sigma_px = 0;  ///< Gaussian blur sigma
  double motion_px = 0;         ///< motion blur length
  double noise_sigma = 0;       ///< sensor noise at mid-grey (linear 0.2), 8-bit code values
  /// Share of the noise variance at mid-grey that is the same at every light level (read noise);
  /// the rest grows with linear light (shot noise). Either is seen through the sRGB curve, whose
  /// slope near black is several times its slope at mid-grey, so below 1 the dark parts of a tag
  /// move by more code values than its bright parts. 1: noise even in code values.
  double read_noise_share = 1.0;
  int jpeg_quality = 0;           ///< 0 = no JPEG round trip, else 1 … 100
  double exposure = 1.0;          ///< overall gain
  double gradient_angle_deg = 0;  ///< direction in which the light falls off (image, clockwise)
  double motion_angle_deg = 0;    ///< direction of the motion blur (image, clockwise)
  /// Sample through a Bayer colour filter array and demosaic bilinearly, as a cheap camera does:
  /// colour fringes along sharp edges, colour noise.
  bool bayer = false;
  int bayer_phase = 0;  ///< 0 … 3: RGGB, GRBG, GBRG, BGGR
  /// Demosaic by OpenCV's variable number of gradients instead of bilinearly: an edge-directed
  /// demosaic, whose false colour on small regions is unlike the bilinear one's. Moderate and Hard
  /// leave it off; pintag_bench and the reader probe set it with --vng-demosaic.
  bool vng_demosaic = false;
  // A phone's processing after the sensor, in 8-bit sRGB before the JPEG (the tuning world's own;
  // the held-out world's phone is PhoneCapture, made differently):
  double tone_gamma = 1.0;        ///< power on code values / 255 (below 1 brightens)
  double saturation = 1.0;        ///< each channel's difference from the channels' mean, scaled
  double chroma_denoise_px = 0;   ///< Gaussian sigma on those differences (colour noise reduction)
  double sharpen = 0;             ///< unsharp mask on every channel, amount
  double sharpen_sigma_px = 1.0;  ///< its Gaussian
  /// An S-shaped tone curve after the power, as phones apply for contrast: each value v (0 … 1)
  /// moved this share of the way to the smoothstep 3 v² − 2 v³, 0 … 1 (slope 1 − c at black and
  /// white, 1 + c / 2 at mid-grey). Moderate and Hard leave it 0; pintag_bench and the reader
  /// probe draw it with --s-curve.
  double tone_contrast = 0;
  /// Random mild settings: gradient 0 … 0.3, any cast or none, defocus σ 0 … 1 px, motion blur
  /// 0 … 2 px half the time, noise σ 1 … 4, JPEG quality 75 … 95, exposure 0.8 … 1.15; tone gamma
  /// 0.85 … 1.15, saturation 0.95 … 1.3, colour denoising σ 0.5 … 1.5 px half the time, sharpening
  /// 0 … 1 (σ 0.6 … 1.2 px); Bayer three times in four, in any of the four phases; half the time
  /// a sensor's noise (read share 0.1 … 0.5), otherwise even.
  static Photometry Moderate(std::uint64_t seed);
  /// Random harsh settings: gradient 0.3 … 0.6, a cast, defocus σ 0.8 … 2 px, motion blur
  /// 1.5 … 5 px, noise σ 4 … 9, JPEG quality 40 … 95, exposure 0.55 … 1.3, Bayer (RGGB) half the
  /// time; tone gamma 0.75 … 1.25, saturation 0.85 … 1.4, colour denoising σ 0.5 … 2 px seven
  /// times in ten, sharpening 0.3 … 1.6 (σ 0.7 … 1.5 px); half the time a sensor's noise (read
  /// share 0.1 … 0.5), otherwise even.
  static Photometry Hard(std::uint64_t seed);
};

/// How a phone turns the light of a held-out scene into a JPEG, in order: illumination (exposure,
/// falloff, the illuminant's cast left by the white balance) and optics (defocus, motion) in linear
/// light; a Bayer sensor (one colour per pixel, shot and read noise, 12 bits) and an edge-aware
/// demosaic; the sRGB curve with an S-shaped contrast curve, a saturation boost and an unsharp mask
/// on luma; a 4:2:0 JPEG (4:4:4 on request) through libjpeg (TurboJPEG), decoded as any image
/// viewer decodes it.
struct PhoneCapture {
  double exposure = 1.0;                  ///< overall gain
  double gradient = 0;                    ///< brightness falloff across the frame, 0 … 0.5
  double gradient_angle_deg = 0;          ///< direction of the falloff (image, clockwise)
  cv::Matx33d cast = cv::Matx33d::eye();  ///< linear-light BGR → BGR the white balance left
  double defocus_sigma_px = 0;            ///< Gaussian blur sigma
  double motion_px = 0;                   ///< motion blur length
  double motion_angle_deg = 0;            ///< its direction (image, clockwise)
  int bayer_phase = 0;                    ///< 0 … 3: RGGB, GRBG, GBRG, BGGR
  double read_noise = 0;                  ///< standard deviation, linear light (0 … 1)
  double shot_noise = 0;                  ///< variance per unit of linear light
  double contrast = 0;                    ///< S-curve strength after the sRGB curve, 0 … 0.5
  double saturation = 1.0;                ///< chroma gain in YCbCr
  double sharpen_amount = 0;              ///< unsharp mask on luma, 0 = none
  double sharpen_sigma_px = 1.0;          ///< its Gaussian
  int jpeg_quality = 90;                  ///< 1 … 100; 0: no JPEG (analysis only)
  /// 4:4:4 instead of the 4:2:0 phones save: what a reader gains from full-resolution colour.
  bool jpeg_full_chroma = false;
  /// false: every pixel senses all three colours, no demosaic (analysis only: what the colour
  /// filter array costs a reader, pintag_genie_probe --mismatch).
  bool mosaic = true;
  /// The sensor's pixels per output pixel along each axis: 2 is a phone that senses and
  /// demosaics at twice the saved image's resolution and then scales it down (analysis only; the
  /// held-out world's phone is 1). The noise is scaled to stay the same per output pixel.
  int sensor_scale = 1;
  /// Mild: exposure 0.8 … 1.15, falloff ≤ 0.25, a mild cast or none, defocus σ 0.2 … 0.8 px, a
  /// little motion blur now and then, noise about 1 … 3 code values at mid-grey, quality 75 … 95,
  /// light sharpening.
  static PhoneCapture Moderate(std::uint64_t seed);
  /// Harsh: exposure 0.5 … 1.3, falloff 0.2 … 0.5, a strong cast, defocus σ 0.6 … 1.5 px,
  /// motion blur 1 … 4 px, noise about 3 … 8 code values at mid-grey, quality 45 … 90, strong
  /// sharpening and contrast.
  static PhoneCapture Hard(std::uint64_t seed);
};

/// Something stuck on or held over a marker (tape, a finger): a filled disk drawn on the marker's
/// surface. Coordinates in square units: x right, y down, origin at the square's top-left corner,
/// side 1 (the PinTag element centres are at 0.25 / 0.75).
struct Occluder {
  cv::Point2d centre{0.25, 0.25};
  double radius = 0.23;
  cv::Scalar bgr{150, 190, 225};  ///< default: skin / masking-tape beige
};

/// An occluder that fully covers PinTag element `element` (0 … 3, C0 … C3: its green ring has
/// radius 0.20) without touching the black square's outline.
Occluder CoverElement(int element);

struct PlacedMarker {
  MarkerTexture texture;
  double square_side_m = 0.05;
  Pose pose;
  int id = -1;  ///< the truth this marker carries (PinTag key, ArUco / AprilTag id)
  std::vector<Occluder> occluders;  ///< drawn over the texture; marks the truth not fully visible
};

struct SceneSpec {
  World world = World::kTuning;  ///< photographs, rendering path and which photometry applies
  Camera camera;
  std::vector<PlacedMarker> markers;
  Photometry photometry;  ///< the tuning world's degradations
  PhoneCapture capture;   ///< the held-out world's
  /// Held-out world: the print's colour error and paper (ink never matches the file exactly).
  std::uint64_t print_seed = 0;
  std::uint64_t seed = 1;       ///< background choice and noise
  bool real_background = true;  ///< a photograph of the world's list, else procedural clutter
  /// With real_background: the index into BackgroundPhotos(world) of the one photograph to crop;
  /// −1 = chosen by the seed, sometimes as a collage of 2 × 2 or 3 × 3 crops of several photos.
  int background_photo = -1;
  /// Sub-samples per pixel side for markers; 0 = automatic: 4 up to a 160 px square, 3 to 320,
  /// 2 to 640, else 1 (the texture is always sampled bilinearly from a suitable mip level).
  int supersample = 0;
};

struct MarkerTruth {
  int id = -1;
  std::array<cv::Point2d, 4> corners_px;  ///< projected square corners, C0 … C3
  Pose pose;
  double square_px = 0;  ///< mean projected side length, pixels
  /// All of the square inside the frame, in front of the camera, no occluder on it and no nearer
  /// marker (quiet zone included) overlapping it.
  bool fully_visible = true;
  cv::Matx33d homography = cv::Matx33d::eye();  ///< square units (0 … 1, as Occluder) → image px
};

struct Scene {
  cv::Mat bgr;  ///< CV_8UC3, camera.width × camera.height
  std::vector<MarkerTruth> truth;
  std::string background;  ///< which background: file name(s) joined by '+', or "procedural"
};

/// Renders the scene: background, markers far to near, then the degradations. Tuning world: each
/// marker inverse-mapped through its homography at `supersample`² points per pixel, blended in
/// linear light, then `photometry` (about 40 … 90 ms for a 1080p frame on one core of the 2-core
/// machines). Held-out world: each marker printed (`print_seed`), reduced by area averaging to the
/// pyramid level nearest its size in the frame, warped bilinearly and blended in sRGB, then
/// `capture`.
Scene RenderScene(const SceneSpec& spec);

/// A point in square units (x, y ∈ [0, 1], origin at C0) mapped to image pixels through
/// `truth.homography`; e.g. PinTag element 2's centre is (0.75, 0.75).
cv::Point2d ProjectSquarePoint(const MarkerTruth& truth, cv::Point2d square_point);

/// A PinTag texture for `key` from the project's renderer (square `square_px` pixels, at least
/// 64). The last 64 textures made are cached (the renderer takes ~20 ms at 512 px).
MarkerTexture PinTagTexture(int key, int square_px = 512);

/// An ArUco DICT_5X5_1000 marker (id 0 … 999) with one-cell black border, its black square about
/// `square_px` pixels (rounded to a multiple of 7 cells), the palette's black, a white quiet zone
/// of 0.15 of the square as for PinTag. cv::aruco reports corners in C0 … C3 order, pixel centres
/// at integers (same convention as the truth).
MarkerTexture ArucoTexture(int id, int square_px = 511);

/// An AprilTag tag36h10 marker (id 0 … 2319), its black square (the 8-cell border) about
/// `square_px` pixels (rounded to a multiple of 8), palette black, white quiet zone as above.
/// Comparing with libapriltag's detections: its p[0 … 3] are C3, C2, C1, C0 (counter-clockwise in
/// the image from the tag's bottom-left) and its pixel centres are at +0.5 (subtract 0.5).
MarkerTexture AprilTagTexture(int id, int square_px = 512);

/// The world's background photographs, a fixed list in a fixed order. Tuning: 22 colour photos
/// from the Debian package opencv-doc (fruit, sweets, a baboon, buildings, …). Held out: 15 from
/// python3-skimage (an astronaut, a cat, coffee, a red motorcycle, a retina, a colour wheel, grey
/// textures, …) and 2 from lomiri-wallpapers-20.04. Blind: 13 from mate-backgrounds (flowers, a
/// ladybird, leaves, grass, a storm, wood, a painting). `scripts/setup.sh test` installs the
/// packages; a missing file throws std::runtime_error naming its package.
const std::vector<std::string>& BackgroundPhotos(World world = World::kTuning);

/// What a printed label carries where its tag goes.
enum class LabelMarker { kPinTag, kAruco, kAprilTag, kNone };

/// A 100 × 150 mm shipping label at 300 dpi as the counter prints it (pintag::label's layout and
/// text), carrying `marker` with `id` in the tag's place at the tag's size (black square and
/// quiet zone; kNone leaves the place white). The texture's square corners are that place's.
MarkerTexture PrintedLabel(LabelMarker marker, int id);

}  // namespace pintag::scene
