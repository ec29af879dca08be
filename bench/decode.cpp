// pintag_bench_decode: Google Benchmark of decoding one 1080p phone-like JPEG (a rendered scene
// with four PinTags, 4:2:0 at quality 90, with an EXIF block holding orientation and focal
// length, as a phone writes) by each path a photo can take:
//   Loader/TurboJpeg        LoadImageBytes: libjpeg-turbo straight to BGR, EXIF through
//                           OpenImageIO's decode_exif (what /api/v1/detect does)
//   Loader/TurboJpegHalf    the same at 1/2 scale (libjpeg-turbo skips the work)
//   Loader/JpegPlanes       Y at full size, Cb and Cr as stored (half size)
//   Baseline/CvImdecode     cv::imdecode(IMREAD_COLOR), OpenCV's own reader
//   Baseline/OpenImageIo    the loader before libjpeg-turbo: OpenImageIO reads RGB, then a copy to
//                           BGR (kept here to show the difference)
// One thread; quote the ratios, or the figures with the machine (the benchmark prints its CPU).

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <benchmark/benchmark.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <vector>

#include "pintag/detector/image_io.hpp"
#include "pintag/scene/scene.hpp"
#include "sweep.hpp"

namespace pintag::bench {
namespace {

/// The stage benchmark's frame (bench/stages.cpp), written as a phone would write it.
std::vector<std::uint8_t> PhoneJpeg() {
  scene::SceneSpec spec;
  spec.seed = 20261122;
  spec.background_photo = 0;
  spec.photometry = scene::Photometry::Moderate(spec.seed);
  const struct {
    int side;
    double x, y, tilt, axis, roll;
  } kTags[] = {{160, 400, 300, 0, 0, 10},
               {80, 1300, 280, 40, 30, 200},
               {48, 700, 800, 55, 120, 75},
               {32, 1500, 800, 20, 250, 300}};
  int key = 101;
  for (const auto& t : kTags) {
    scene::PlacedMarker m;
    m.id = key * 37;
    m.texture = scene::PinTagTexture(m.id);
    m.square_side_m = kTagSideM;
    m.pose = scene::MakePose(spec.camera, {t.x, t.y},
                             scene::DistanceForSquarePx(spec.camera, t.side, kTagSideM), t.tilt,
                             t.axis, t.roll);
    spec.markers.push_back(std::move(m));
    ++key;
  }
  const cv::Mat bgr = scene::RenderScene(spec).bgr;
  cv::Mat rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);

  std::vector<unsigned char> bytes;
  OIIO::Filesystem::IOVecOutput proxy(bytes);
  OIIO::Filesystem::IOProxy* proxy_pointer = &proxy;
  OIIO::ImageSpec out_spec(rgb.cols, rgb.rows, 3, OIIO::TypeDesc::UINT8);
  out_spec.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy_pointer);
  out_spec.attribute("Compression", "jpeg:90");
  out_spec.attribute("Orientation", 1);
  out_spec.attribute("Exif:FocalLength", 4.25f);
  out_spec.attribute("Exif:FocalLengthIn35mmFilm", 26);
  auto out = OIIO::ImageOutput::create("jpg");
  if (!out || !out->open("phone.jpg", out_spec) ||
      !out->write_image(OIIO::TypeDesc::UINT8, rgb.data) || !out->close()) {
    throw std::runtime_error("cannot write the phone JPEG: " + OIIO::geterror());
  }
  return {bytes.begin(), bytes.end()};
}

// Google Benchmark's names and its `for (auto _ : state)` loop, as in stages.cpp.
// NOLINTBEGIN(readability-identifier-naming, clang-analyzer-deadcode.DeadStores)
const std::vector<std::uint8_t>& Jpeg() {
  static const std::vector<std::uint8_t> jpeg = PhoneJpeg();
  return jpeg;
}

void BM_Loader_TurboJpeg(benchmark::State& state) {
  const auto& jpeg = Jpeg();
  for (auto _ : state) {
    LoadResult r = LoadImageBytes(jpeg);
    if (!r.image) state.SkipWithError(r.error.c_str());
    benchmark::DoNotOptimize(r);
  }
  state.SetLabel("1920x1080 4:2:0 q90, " + std::to_string(jpeg.size() / 1024) + " KiB");
}
BENCHMARK(BM_Loader_TurboJpeg)->Unit(benchmark::kMillisecond);

void BM_Loader_TurboJpegHalf(benchmark::State& state) {
  const auto& jpeg = Jpeg();
  LoadOptions options;
  options.scale_denominator = 2;
  for (auto _ : state) {
    LoadResult r = LoadImageBytes(jpeg, options);
    if (!r.image) state.SkipWithError(r.error.c_str());
    benchmark::DoNotOptimize(r);
  }
}
BENCHMARK(BM_Loader_TurboJpegHalf)->Unit(benchmark::kMillisecond);

void BM_Loader_JpegPlanes(benchmark::State& state) {
  const auto& jpeg = Jpeg();
  for (auto _ : state) {
    JpegPlanesResult r = LoadJpegPlanes(jpeg);
    if (!r.planes) state.SkipWithError(r.error.c_str());
    benchmark::DoNotOptimize(r);
  }
}
BENCHMARK(BM_Loader_JpegPlanes)->Unit(benchmark::kMillisecond);

void BM_Baseline_CvImdecode(benchmark::State& state) {
  const auto& jpeg = Jpeg();
  for (auto _ : state) {
    cv::Mat bgr = cv::imdecode(jpeg, cv::IMREAD_COLOR);
    benchmark::DoNotOptimize(bgr.data);
  }
}
BENCHMARK(BM_Baseline_CvImdecode)->Unit(benchmark::kMillisecond);

void BM_Baseline_OpenImageIo(benchmark::State& state) {
  const auto& jpeg = Jpeg();
  for (auto _ : state) {
    OIIO::Filesystem::IOMemReader reader(jpeg.data(), jpeg.size());
    OIIO::Filesystem::IOProxy* proxy = &reader;
    OIIO::ImageSpec config;
    config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
    auto input = OIIO::ImageInput::open("image.jpg", &config);
    const OIIO::ImageSpec& spec = input->spec();
    std::vector<std::uint8_t> rgb(static_cast<std::size_t>(spec.width) * spec.height * 3);
    input->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, rgb.data());
    cv::Mat bgr(spec.height, spec.width, CV_8UC3);
    cv::cvtColor(cv::Mat(spec.height, spec.width, CV_8UC3, rgb.data()), bgr, cv::COLOR_RGB2BGR);
    benchmark::DoNotOptimize(bgr.data);
  }
}
BENCHMARK(BM_Baseline_OpenImageIo)->Unit(benchmark::kMillisecond);
// NOLINTEND(readability-identifier-naming, clang-analyzer-deadcode.DeadStores)

}  // namespace
}  // namespace pintag::bench

BENCHMARK_MAIN();
