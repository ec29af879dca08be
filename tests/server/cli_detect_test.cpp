// `pintag detect` as a user runs it: the real binary on a photo file, its JSON on stdout, its
// exit status and message on failure. The photo is a PinTag of the default label's size rendered
// by the scene generator at a known pose.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <thread>

#include "pintag/codec/label.hpp"
#include "pintag/codec/mirror.hpp"
#include "pintag/scene/scene.hpp"
#include "pintag/test/files.hpp"
#include "serve_fixture.hpp"

namespace pintag::serve_test {
namespace {

using nlohmann::json;

struct RenderedPhoto {
  std::string path;
  scene::MarkerTruth truth;
  scene::Camera camera;
};

constexpr int kKey = 11684;  // 110001's key in the seeded registry; any key reads the same

RenderedPhoto RenderPhoto(const test::TempDir& dir) {
  scene::SceneSpec spec;
  spec.seed = 11;
  spec.photometry.noise_sigma = 2;
  scene::PlacedMarker marker;
  marker.id = kKey;
  marker.texture = scene::PinTagTexture(kKey);
  marker.square_side_m = TagPlacement(kLabel100x150).square_side_mm / 1000;
  const double distance = scene::DistanceForSquarePx(spec.camera, 160, marker.square_side_m);
  marker.pose = scene::MakePose(spec.camera, {1100, 420}, distance, 25, 60, 15);
  spec.markers.push_back(marker);
  const scene::Scene rendered = scene::RenderScene(spec);
  RenderedPhoto photo{(dir.path() / "photo.png").string(), rendered.truth.at(0), spec.camera};
  EXPECT_TRUE(cv::imwrite(photo.path, rendered.bgr));
  return photo;
}

std::string Intrinsics(const scene::Camera& c) {
  return " --fx " + std::to_string(c.fx) + " --fy " + std::to_string(c.fy) + " --cx " +
         std::to_string(c.cx) + " --cy " + std::to_string(c.cy);
}

/// `pintag detect --json <options>` on the photo (intrinsics given): the one detection, or null
/// after a failed assertion.
json DetectOne(const RenderedPhoto& photo, const std::string& options) {
  const CommandResult run =
      RunPintag("detect --json " + options + Intrinsics(photo.camera) + " " + photo.path);
  EXPECT_EQ(run.status, 0) << run.out;
  if (run.status != 0) return nullptr;
  const json answer = json::parse(run.out);
  EXPECT_EQ(answer["detections"].size(), 1U) << run.out;
  return answer["detections"].size() == 1 ? answer["detections"][0] : json(nullptr);
}

TEST(CliDetect, ReadsKeyAndDistanceWithTheDefaultLabelsTagSize) {
  const test::TempDir dir;
  const RenderedPhoto photo = RenderPhoto(dir);
  const json tag = DetectOne(photo, "");
  ASSERT_FALSE(tag.is_null());
  EXPECT_EQ(tag["key"], kKey);
  // No --tag-size-mm: the default is the 100 x 150 mm label's tag, as for /api/v1/detect, so
  // the distance comes out right for the label the counter printed.
  const double truth_m = cv::norm(photo.truth.pose.translation);
  EXPECT_NEAR(tag["pose"]["distance_m"].get<double>(), truth_m, 0.02 * truth_m);
}

TEST(CliDetect, DistanceScalesWithTheGivenTagSize) {
  const test::TempDir dir;
  const RenderedPhoto photo = RenderPhoto(dir);
  const json tag = DetectOne(photo, "--tag-size-mm 50");
  ASSERT_FALSE(tag.is_null());
  const double truth_m =
      cv::norm(photo.truth.pose.translation) * 50 / TagPlacement(kLabel100x150).square_side_mm;
  EXPECT_NEAR(tag["pose"]["distance_m"].get<double>(), truth_m, 0.02 * truth_m);
}

TEST(CliDetect, DistortionTakesTheCountsOpenCvReadsAndNeedsTheFocalLengths) {
  const test::TempDir dir;
  const RenderedPhoto photo = RenderPhoto(dir);
  const std::string intrinsics = " --fx 1000 --fy 1000";
  // 6 or 7 coefficients made OpenCV's pose solver return nothing, reported as a zero pose.
  for (const std::string& options :
       {intrinsics + " --distortion 0 0 0 0 0 0", intrinsics + " --distortion 0 0 0 0 0 0 0",
        std::string(" --distortion 0 0 0 0"), intrinsics + " --distortion 0 0 nan 0"}) {
    const CommandResult refused = RunPintag("detect " + photo.path + options);
    EXPECT_EQ(refused.status, 2) << options << ": " << refused.out;
  }
  for (const std::string& options :
       {intrinsics + " --distortion 0 0 0 0", intrinsics + " --distortion 0 0 0 0 0",
        intrinsics + " --distortion 0 0 0 0 0 0 0 0"}) {
    const CommandResult read = RunPintag("detect --json " + photo.path + options);
    EXPECT_EQ(read.status, 0) << options << ": " << read.out;
    const json answer = json::parse(read.out, nullptr, false);
    ASSERT_FALSE(answer.is_discarded()) << read.out;
    ASSERT_EQ(answer["detections"].size(), 1U) << options;
    EXPECT_GT(answer["detections"][0]["pose"]["distance_m"].get<double>(), 0.01) << options;
  }
}

TEST(CliDetect, RefusesWhatIsNotAPhotoWithAClearMessage) {
  const test::TempDir dir;
  const std::string text = (dir.path() / "notes.txt").string();
  test::WriteFile(text, "this is not a photo\n");
  const CommandResult not_image = RunPintag("detect " + text);
  EXPECT_NE(not_image.status, 0);
  EXPECT_NE(not_image.out.find("notes.txt"), std::string::npos) << not_image.out;

  const CommandResult missing = RunPintag("detect " + (dir.path() / "nowhere.jpg").string());
  EXPECT_NE(missing.status, 0);
  EXPECT_NE(missing.out.find("nowhere.jpg: No such file or directory"), std::string::npos)
      << missing.out;

  const CommandResult directory = RunPintag("detect " + dir.path().string());
  EXPECT_NE(directory.status, 0);
  EXPECT_NE(directory.out.find("is a directory, not a photo"), std::string::npos) << directory.out;

  const CommandResult bad_size = RunPintag("detect --tag-size-mm 0 " + text);
  EXPECT_NE(bad_size.status, 0);
  EXPECT_NE(bad_size.out.find("tag-size-mm"), std::string::npos) << bad_size.out;
}

TEST(CliDetect, APrincipalPointWithoutFocalLengthsIsRefusedAsTheApiRefusesIt) {
  // It was ignored: the pose came from assumed intrinsics while the user believed theirs were used.
  const test::TempDir dir;
  const RenderedPhoto photo = RenderPhoto(dir);
  for (const char* options : {" --cx 5", " --cy 5", " --cx 5 --cy 5"}) {
    const CommandResult refused = RunPintag("detect " + photo.path + options);
    EXPECT_EQ(refused.status, 2) << options << ": " << refused.out;
    EXPECT_NE(refused.out.find("--cx and --cy need --fx and --fy"), std::string::npos)
        << options << ": " << refused.out;
  }
  const CommandResult given = RunPintag("detect " + photo.path + Intrinsics(photo.camera));
  EXPECT_EQ(given.status, 0) << given.out;
  EXPECT_NE(given.out.find("intrinsics given"), std::string::npos) << given.out;
}

TEST(CliDetect, AWrongCommandLineIsExitTwoEvenWhenThePhotoIsMissing) {
  const test::TempDir dir;
  const std::string missing = dir.file("missing.jpg");
  for (const std::string& options :
       {std::string(" --fx 1000 --fy 1000 --distortion 1 2 3 4 5 6"), std::string(" --fx 1000"),
        std::string(" --cx 5"), std::string(" --distortion 0 0 0 0"),
        " --debug-dir " + WriteFile(dir.path() / "afile", "x"),
        " --overlay " + dir.file("overlay.txt"), " --overlay " + dir.file("overlay")}) {
    const CommandResult refused = RunPintag(std::string("detect ").append(missing).append(options));
    EXPECT_EQ(refused.status, 2) << options << ": " << refused.out;
    EXPECT_EQ(refused.out.find("cannot open"), std::string::npos) << options << ": " << refused.out;
  }
  // An extension OpenCV knows but does not write: Debian's OpenCV switches OpenEXR off unless
  // OPENCV_IO_ENABLE_OPENEXR is set, and the overlay failed after the whole detection.
  const CommandResult exr = RunShell("env -u OPENCV_IO_ENABLE_OPENEXR " + PintagExe() + " detect " +
                                     missing + " --overlay " + dir.file("overlay.exr") + " 2>&1");
  EXPECT_EQ(exr.status, 2) << exr.out;
  EXPECT_NE(exr.out.find("no image format"), std::string::npos) << exr.out;
  // Right options and a missing photo: the job fails (1).
  EXPECT_EQ(RunPintag("detect " + missing + " --fx 1000 --fy 1000 --distortion 0 0 0 0").status, 1);
}

// A candidate that did not decode is listed with --rejected, but it is not a tag: the headline
// counted it as one ("1 tag(s)" above "rejected candidate: parity check failed").
TEST(CliDetect, RejectedCandidatesAreCountedApartFromTags) {
  const test::TempDir dir;
  int key = 1234;  // a key whose mirror image is no codeword, so a mirrored tag is refused
  while (MirrorImageKey(TagKey(static_cast<std::uint16_t>(key)))) ++key;
  const std::string tag = dir.file("tag.png");
  ASSERT_EQ(RunPintag("render --key " + std::to_string(key) + " --size-px 256 -o " + tag).status,
            0);
  cv::Mat mirrored;
  cv::flip(cv::imread(tag), mirrored, 1);
  const std::string photo = dir.file("mirrored.png");
  ASSERT_TRUE(cv::imwrite(photo, mirrored));
  const CommandResult refused = RunPintag("detect " + photo + " --rejected");
  EXPECT_EQ(refused.status, 0) << refused.out;
  EXPECT_EQ(refused.out.rfind("0 tag(s), 1 rejected candidate(s) in " + photo, 0), 0U)
      << refused.out;
  EXPECT_NE(refused.out.find("rejected candidate  corners ("), std::string::npos) << refused.out;
  const CommandResult read = RunPintag("detect " + tag + " --rejected");
  EXPECT_EQ(read.out.rfind("1 tag(s), 0 rejected candidate(s) in " + tag, 0), 0U) << read.out;
  EXPECT_EQ(RunPintag("detect " + photo).out.rfind("0 tag(s) in " + photo, 0), 0U);
}

// The API's ranges: beyond them the pose was NaN ("distance nan m") with exit 0. A number is read
// as the API reads it: no hexadecimal, no spaces.
TEST(CliDetect, IntrinsicsOutsideTheApisRangesAreRefused) {
  const test::TempDir dir;
  const std::string detect_missing = "detect " + dir.file("missing.jpg");
  for (const std::string& options :
       {std::string(" --fx 1e308 --fy 1e308"), std::string(" --fx 0 --fy 500"),
        std::string(" --fx 500 --fy 2e7"), std::string(" --fx 500 --fy 500 --cx 2e6"),
        std::string(" --fx 500 --fy 500 --distortion 1e300 1e300 0 0"),
        std::string(" --fx 0x1F4 --fy 500"), std::string(" --fx ' 500' --fy 500"),
        std::string(" --max-pixels 99999999999"), std::string(" --max-pixels 0")}) {
    const CommandResult refused = RunPintag(detect_missing + options);
    EXPECT_EQ(refused.status, 2) << options << ": " << refused.out;
    // Said in a sentence, not with DBL_MAX's 309 digits.
    EXPECT_LT(refused.out.size(), 400U) << options << ": " << refused.out;
  }
  const CommandResult range = RunPintag(detect_missing + " --fx 1e308 --fy 1e308");
  EXPECT_NE(range.out.find("must be a number from 0.001 to 1e+07, got '1e308'"), std::string::npos)
      << range.out;
  const CommandResult size = RunPintag("render --key 12 --size-mm 0x10 -o " + dir.file("t.png"));
  EXPECT_EQ(size.status, 2) << size.out;
  EXPECT_FALSE(std::filesystem::exists(dir.file("t.png")));
}

TEST(CliDetect, ADashReadsThePhotoFromStandardInput) {
  const test::TempDir dir;
  const RenderedPhoto photo = RenderPhoto(dir);
  const CommandResult from_file = RunPintag("detect --json " + photo.path);
  const CommandResult piped = RunShell(PintagExe() + " detect --json - < " + photo.path);
  ASSERT_EQ(from_file.status, 0) << from_file.out;
  ASSERT_EQ(piped.status, 0) << piped.out;
  const json a = json::parse(from_file.out);
  const json b = json::parse(piped.out);
  ASSERT_EQ(a["detections"].size(), 1U);
  ASSERT_EQ(b["detections"].size(), 1U);
  EXPECT_EQ(a["detections"][0]["key"], b["detections"][0]["key"]);
  EXPECT_EQ(a["detections"][0]["corners_px"], b["detections"][0]["corners_px"]);
}

TEST(CliDetect, HelpSaysHowManyDistortionNumbersItTakes) {
  const CommandResult help = RunPintag("detect --help");
  EXPECT_EQ(help.status, 0) << help.out;
  EXPECT_NE(help.out.find("--distortion K1 K2 P1 P2 [K3 [K4 K5 K6]]"), std::string::npos)
      << help.out;
  EXPECT_NE(help.out.find("4, 5 or 8 numbers"), std::string::npos) << help.out;
  EXPECT_EQ(help.out.find(" x 4"), std::string::npos) << help.out;
}

TEST(CliDetect, ADebugDirThatIsAFileIsRefusedAndAGoodOneGetsEveryStage) {
  const test::TempDir dir;
  const RenderedPhoto photo = RenderPhoto(dir);
  const std::string file = WriteFile(dir.path() / "afile", "not a directory\n");
  const CommandResult refused = RunPintag("detect " + photo.path + " --debug-dir " + file);
  EXPECT_EQ(refused.status, 2) << refused.out;
  EXPECT_NE(refused.out.find("is not a directory"), std::string::npos) << refused.out;
  EXPECT_EQ(ReadFile(file), "not a directory\n");

  // A photo that cannot be read leaves no directory behind (it was made before the photo).
  const std::string unmade = dir.file("unmade");
  const CommandResult unread =
      RunPintag("detect " + dir.file("no-such-photo.jpg") + " --debug-dir " + unmade);
  EXPECT_EQ(unread.status, 1) << unread.out;
  EXPECT_FALSE(std::filesystem::exists(unmade));

  const std::string debug = dir.file("stages/deeper");
  const CommandResult written = RunPintag("detect " + photo.path + " --debug-dir " + debug);
  EXPECT_EQ(written.status, 0) << written.out;
  for (const char* stage : {"1_redness.png", "2_blobs.png", "3_quads.png", "4_detections.png"}) {
    EXPECT_TRUE(std::filesystem::is_regular_file(std::filesystem::path(debug) / stage)) << stage;
  }
}

TEST(CliDetect, AnOverlayPathThatIsThePhotoIsRefusedAndThePhotoKept) {
  const test::TempDir dir;
  const RenderedPhoto photo = RenderPhoto(dir);
  const std::string before = ReadFile(photo.path);
  const std::string link = dir.file("link.png");
  std::filesystem::create_symlink(photo.path, link);
  for (const std::string& overlay : {photo.path, link, (dir.path() / "." / "photo.png").string()}) {
    const CommandResult refused = RunPintag("detect " + photo.path + " --overlay " + overlay);
    EXPECT_EQ(refused.status, 2) << overlay << ": " << refused.out;
    EXPECT_NE(refused.out.find("is the photo itself"), std::string::npos) << refused.out;
    // The photo given on standard input (`detect - < photo.png`) is the same file.
    const CommandResult piped =
        RunShell(PintagExe() + " detect - --overlay " + overlay + " < " + photo.path + " 2>&1");
    EXPECT_EQ(piped.status, 2) << overlay << ": " << piped.out;
    EXPECT_NE(piped.out.find("the photo itself"), std::string::npos) << piped.out;
  }
  EXPECT_EQ(ReadFile(photo.path), before);
  // Where an overlay cannot go is a usage error before the photo is searched, output or not.
  std::filesystem::create_directory(dir.path() / "adir.png");
  for (const std::string& overlay :
       {dir.file("no-such-dir/seen.png"), dir.file("adir.png"), dir.file("adir.png") + "/"}) {
    const CommandResult refused =
        RunPintag("detect --json " + photo.path + " --overlay " + overlay);
    EXPECT_EQ(refused.status, 2) << overlay << ": " << refused.out;
    EXPECT_EQ(refused.out.find("\"detections\""), std::string::npos) << refused.out;
    EXPECT_NE(refused.out.find("directory"), std::string::npos) << refused.out;
  }

  const std::string seen = dir.file("seen.png");
  const CommandResult drawn = RunPintag("detect " + photo.path + " --overlay " + seen);
  EXPECT_EQ(drawn.status, 0) << drawn.out;
  EXPECT_EQ(cv::imread(seen).size(), cv::imread(photo.path).size());
}

// The stage images replace files of their names: `detect dd/4_detections.png --debug-dir dd`
// wrote the last stage over the photo, and an overlay named as a stage was overwritten by it.
TEST(CliDetect, StageImagesNeverReplaceThePhotoOrTheOverlay) {
  const test::TempDir dir;
  const RenderedPhoto rendered = RenderPhoto(dir);
  const std::filesystem::path stages = dir.path() / "stages";
  std::filesystem::create_directory(stages);
  const std::string photo = (stages / "4_detections.png").string();
  std::filesystem::copy_file(rendered.path, photo);
  const std::string before = ReadFile(photo);
  const std::string detect_photo = "detect " + photo + " --debug-dir ";
  const std::string detect_stdin = PintagExe() + " detect - --debug-dir ";
  const std::string from_photo = " < " + photo + " 2>&1";
  for (const std::string& debug : {stages.string(), (dir.path() / "." / "stages").string()}) {
    const CommandResult refused = RunPintag(detect_photo + debug);
    EXPECT_EQ(refused.status, 2) << refused.out;
    EXPECT_NE(refused.out.find("would write 4_detections.png over the photo"), std::string::npos)
        << refused.out;
    std::string piped_line = detect_stdin;
    piped_line += debug;
    piped_line += from_photo;
    const CommandResult piped = RunShell(piped_line);
    EXPECT_EQ(piped.status, 2) << piped.out;
    EXPECT_NE(piped.out.find("over the photo"), std::string::npos) << piped.out;
  }
  EXPECT_TRUE(ReadFile(photo) == before);  // not EXPECT_EQ: a PNG's bytes are no message
  EXPECT_FALSE(std::filesystem::exists(stages / "1_redness.png"));

  const std::string overlay = (stages / "3_quads.png").string();
  const CommandResult over_overlay = RunPintag("detect " + rendered.path + " --debug-dir " +
                                               stages.string() + " --overlay " + overlay);
  EXPECT_EQ(over_overlay.status, 2) << over_overlay.out;
  EXPECT_NE(over_overlay.out.find("would write 3_quads.png over the overlay"), std::string::npos)
      << over_overlay.out;
  EXPECT_FALSE(std::filesystem::exists(overlay));
  // Beside the stages, under a name of its own, the overlay is written with them.
  const std::string beside = (stages / "seen.png").string();
  const CommandResult both = RunPintag("detect " + rendered.path + " --debug-dir " +
                                       stages.string() + " --overlay " + beside);
  EXPECT_EQ(both.status, 0) << both.out;
  EXPECT_TRUE(std::filesystem::is_regular_file(beside));
  EXPECT_TRUE(std::filesystem::is_regular_file(stages / "1_redness.png"));
}

// `detect - < /dev/zero` read standard input to its 1 GiB limit (2.2 GB at the peak) before it
// said the input was no photo. Given bytes that are not a photo's start and then nothing more,
// with the pipe left open, it now answers at once instead of waiting for the rest.
TEST(CliDetect, InputThatDoesNotStartAsAPhotoIsRefusedFromItsFirstBytes) {
  const test::TempDir dir;
  int pipe_fds[2];
  ASSERT_EQ(::pipe2(pipe_fds, O_CLOEXEC), 0);
  const std::string err = dir.file("err.txt");
  const pid_t pid = SpawnPintagWith({"detect", "-"}, pipe_fds[0], STDIN_FILENO, err);
  ::close(pipe_fds[0]);
  ASSERT_GT(pid, 0);
  // More than one read's worth (64 KiB) of zeros, and the pipe kept open. The command may stop
  // reading, and exit, before the last of them is in the pipe: that write then fails (EPIPE)
  // rather than ending this test with SIGPIPE.
  const std::string zeros(70000, '\0');
  struct sigaction ignore {};
  struct sigaction before {};
  ignore.sa_handler = SIG_IGN;
  ::sigaction(SIGPIPE, &ignore, &before);
  std::size_t written = 0;
  while (written < zeros.size()) {
    const ssize_t n = ::write(pipe_fds[1], zeros.data() + written, zeros.size() - written);
    if (n <= 0) break;
    written += static_cast<std::size_t>(n);
  }
  ::sigaction(SIGPIPE, &before, nullptr);
  ASSERT_GE(written, std::size_t{1} << 16) << "the command stopped reading before one read's worth";
  int status = 0;
  pid_t ended = 0;
  // Not a time limit on the command: a bound on how long this test waits for one that is stuck.
  for (int i = 0; i < 600 && ended == 0; ++i) {
    ended = ::waitpid(pid, &status, WNOHANG);
    if (ended == 0) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  if (ended == 0) {
    ::kill(pid, SIGKILL);
    ::waitpid(pid, &status, 0);
  }
  ::close(pipe_fds[1]);
  ASSERT_NE(ended, 0) << "detect waited for more input after bytes that are no photo";
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 1);
  EXPECT_NE(ReadFile(err).find("standard input: not a JPEG, PNG, TIFF or WebP image"),
            std::string::npos)
      << ReadFile(err);
}

}  // namespace
}  // namespace pintag::serve_test
