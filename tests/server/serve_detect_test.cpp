// POST /api/v1/detect on a real `pintag serve`: a label fetched from the server, photographed in a
// synthetic scene at a known pose, uploaded, read back; and every way an upload can be wrong.

#include <OpenImageIO/imageio.h>
#include <openssl/evp.h>
#include <unistd.h>
#include <zlib.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <thread>
#include <vector>

#include "label_photo.hpp"
#include "pintag/codec/label.hpp"
#include "pintag/codec/mirror.hpp"
#include "pintag/db/database.hpp"
#include "pintag/db/scan_log.hpp"
#include "pintag/scene/scene.hpp"
#include "pintag/test/loopback_socket.hpp"
#include "serve_fixture.hpp"

namespace pintag::serve_test {
namespace {

using nlohmann::json;

double RotationErrorDeg(const json& rotation_vector, const cv::Matx33d& truth) {
  const cv::Vec3d rvec(rotation_vector[0].get<double>(), rotation_vector[1].get<double>(),
                       rotation_vector[2].get<double>());
  cv::Matx33d estimate;
  cv::Rodrigues(rvec, estimate);
  const cv::Matx33d delta = estimate * truth.t();
  const double c = std::clamp((cv::trace(delta) - 1) / 2, -1.0, 1.0);
  return std::acos(c) * 180 / M_PI;
}

TEST_F(ServeTest, LabelPhotographedInASceneReadsBackPincodeKeyBinAndPose) {
  const Photo photo = PhotographLabel(client(), counter(), "110001", 30);
  ASSERT_FALSE(photo.jpeg.empty());
  const std::string query =
      "/api/v1/detect?plan=default&tag_size_mm=" + std::to_string(photo.square_mm) +
      "&fx=1400&fy=1400&cx=960&cy=540";
  httplib::MultipartFormDataItems form = {{"image", photo.jpeg, "photo.jpg", "image/jpeg"}};
  const json out = ExpectJson(client().Post(query, scanner(), form));
  ASSERT_EQ(out["tags"].size(), 1U) << out.dump(1);
  const json& tag = out["tags"][0];
  EXPECT_EQ(tag["pincode"], "110001");
  EXPECT_EQ(tag["key"], 11684);
  EXPECT_EQ(tag["bin"], "11");
  EXPECT_EQ(tag["status"], "active");
  EXPECT_EQ(tag["district"], "Central Delhi");
  EXPECT_EQ(tag["state"], "Delhi");
  EXPECT_TRUE(tag["office"].is_string());
  EXPECT_EQ(out["image"]["width"], 1920);
  EXPECT_EQ(out["image"]["height"], 1080);
  EXPECT_EQ(out["image"]["chroma_upsampling"], "4:2:0");  // OpenCV's JPEG, as a phone's
  EXPECT_EQ(out["intrinsics"]["source"], "given");
  EXPECT_EQ(out["plan"], "default");
  EXPECT_GT(out["time_ms"]["total"].get<double>(), 0);
  for (int c = 0; c < 4; ++c) {
    EXPECT_NEAR(tag["corners_px"][c][0].get<double>(), photo.truth.corners_px[c].x, 1.0);
    EXPECT_NEAR(tag["corners_px"][c][1].get<double>(), photo.truth.corners_px[c].y, 1.0);
  }
  const cv::Point2d centre = scene::ProjectSquarePoint(photo.truth, {0.5, 0.5});
  EXPECT_NEAR(tag["centre_px"][0].get<double>(), centre.x, 1.0);
  EXPECT_NEAR(tag["centre_px"][1].get<double>(), centre.y, 1.0);
  const json& pose = tag["pose"];
  const double true_distance = cv::norm(photo.truth.pose.translation);
  EXPECT_NEAR(pose["distance_m"].get<double>(), true_distance, 0.02 * true_distance);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(pose["translation_m"][i].get<double>(), photo.truth.pose.translation[i],
                0.02 * true_distance);
  }
  EXPECT_LT(RotationErrorDeg(pose["rotation_vector"], photo.truth.pose.rotation), 3.0);
  EXPECT_EQ(pose["quaternion_wxyz"].size(), 4U);
  EXPECT_TRUE(tag["pose_ambiguous"].is_boolean());

  // The same photo as a raw body without intrinsics: same reading, intrinsics assumed.
  const json raw = ExpectJson(client().Post("/api/v1/detect", scanner(), photo.jpeg, "image/jpeg"));
  ASSERT_EQ(raw["tags"].size(), 1U);
  EXPECT_EQ(raw["tags"][0]["pincode"], "110001");
  EXPECT_EQ(raw["intrinsics"]["source"], "assumed");
  EXPECT_NEAR(raw["tag_size_mm"].get<double>(), TagPlacement(kLabel100x150).square_side_mm, 1e-9);

  // ?overlay=1: the photo annotated, as PNG of the same size.
  auto r = client().Post(query + "&overlay=1", admin(), form);
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body.substr(0, 300);
  EXPECT_EQ(r->get_header_value("Content-Type"), "image/png");
  const cv::Mat overlay =
      cv::imdecode(std::vector<std::uint8_t>(r->body.begin(), r->body.end()), cv::IMREAD_COLOR);
  EXPECT_EQ(overlay.cols, 1920);
  EXPECT_EQ(overlay.rows, 1080);

  // Each call is in the scan log, with the token that made it.
  ScanRowsOnceThereAre(db_path_, 3);
  auto opened = db::OpenDatabase(db_path_, {.create = false});
  ASSERT_TRUE(opened);
  auto scans = db::RecentScans(opened.value().connection, 10);
  ASSERT_TRUE(scans);
  ASSERT_EQ(scans->size(), 3U);
  EXPECT_EQ((*scans)[2].image_width, 1920);
  EXPECT_EQ((*scans)[2].image_bytes, static_cast<std::int64_t>(photo.jpeg.size()));
  const json logged = json::parse((*scans)[2].result_json);
  EXPECT_EQ(logged["tags"][0]["pincode"], "110001");
  EXPECT_TRUE((*scans)[2].token_id.has_value());
  EXPECT_NE((*scans)[0].token_id, (*scans)[2].token_id);  // admin made the last call
}

// A sorter that finds a parcel in the wrong bin must be able to tell which registry routed it: the
// answer (and its scan-log row) names the registry version its tags were resolved in, the one
// GET /api/v1/registry gives, and a plan's change shows as a later version beside the new bin.
TEST_F(ServeTest, TheAnswerNamesTheRegistryVersionItsBinsCameFrom) {
  const Photo photo = PhotographLabel(client(), counter(), "110001", 20);
  ASSERT_FALSE(photo.jpeg.empty());
  const std::string query =
      "/api/v1/detect?plan=hub&tag_size_mm=" + std::to_string(photo.square_mm);
  auto put =
      client().Put("/api/v1/sortplans/hub", admin(), "prefix,bin\n*,floor\n11,north\n", "text/csv");
  ASSERT_TRUE(put);
  ASSERT_EQ(put->status, 201) << put->body;
  const json before = ExpectJson(client().Post(query, scanner(), photo.jpeg, "image/jpeg"));
  ASSERT_EQ(before["tags"].size(), 1U) << before.dump(1);
  EXPECT_EQ(before["tags"][0]["bin"], "north");
  const std::int64_t first = ExpectJson(client().Get("/api/v1/registry"))["registry_version"];
  EXPECT_EQ(before["registry_version"].get<std::int64_t>(), first);

  put = client().Put("/api/v1/sortplans/hub", admin(), "prefix,bin\n*,floor\n110,parliament\n",
                     "text/csv");
  ASSERT_TRUE(put);
  ASSERT_EQ(put->status, 200) << put->body;
  const json after = ExpectJson(client().Post(query, scanner(), photo.jpeg, "image/jpeg"));
  ASSERT_EQ(after["tags"].size(), 1U);
  EXPECT_EQ(after["tags"][0]["bin"], "parliament");
  const std::int64_t second = ExpectJson(client().Get("/api/v1/registry"))["registry_version"];
  EXPECT_GT(second, first);
  EXPECT_EQ(after["registry_version"].get<std::int64_t>(), second);
  // A PNG answer (overlay=1) carries it as a header, as does the JSON one.
  const auto png = client().Post(query + "&overlay=1", scanner(), photo.jpeg, "image/jpeg");
  ASSERT_TRUE(png);
  ASSERT_EQ(png->status, 200) << png->body.substr(0, 300);
  EXPECT_EQ(png->get_header_value("Content-Type"), "image/png");
  EXPECT_EQ(png->get_header_value("X-PinTag-Registry-Version"), std::to_string(second));
  const auto plain = client().Post(query, scanner(), photo.jpeg, "image/jpeg");
  ASSERT_TRUE(plain);
  EXPECT_EQ(plain->get_header_value("X-PinTag-Registry-Version"), std::to_string(second));

  ScanRowsOnceThereAre(db_path_, 4);
  auto opened = db::OpenDatabase(db_path_, {.create = false});
  ASSERT_TRUE(opened);
  auto scans = db::RecentScans(opened.value().connection, 1);
  ASSERT_TRUE(scans);
  ASSERT_EQ(scans->size(), 1U);
  EXPECT_EQ(json::parse((*scans)[0].result_json)["registry_version"].get<std::int64_t>(), second);
}

// A camera's black-and-white mode keeps the tag's shape and loses its bits: the answer says so,
// where the same photo in colour is read with no warning.
TEST_F(ServeTest, APhotoWithoutColourReadsNoTagAndTheAnswerSaysWhy) {
  const Photo photo = PhotographLabel(client(), counter(), "110001", 20);
  ASSERT_FALSE(photo.jpeg.empty());
  const json colour =
      ExpectJson(client().Post("/api/v1/detect", scanner(), photo.jpeg, "image/jpeg"));
  ASSERT_EQ(colour["tag_count"], 1);
  EXPECT_EQ(colour["warnings"], json::array());

  const cv::Mat decoded = cv::imdecode(
      std::vector<std::uint8_t>(photo.jpeg.begin(), photo.jpeg.end()), cv::IMREAD_COLOR);
  cv::Mat grey;
  cv::cvtColor(decoded, grey, cv::COLOR_BGR2GRAY);
  for (const bool stored_as_colour : {false, true}) {
    cv::Mat saved = grey;
    if (stored_as_colour) cv::cvtColor(grey, saved, cv::COLOR_GRAY2BGR);
    std::vector<std::uint8_t> jpeg;
    ASSERT_TRUE(cv::imencode(".jpg", saved, jpeg, {cv::IMWRITE_JPEG_QUALITY, 90}));
    const json out = ExpectJson(client().Post("/api/v1/detect", scanner(),
                                              std::string(jpeg.begin(), jpeg.end()), "image/jpeg"));
    EXPECT_EQ(out["tag_count"], 0) << "stored as colour " << stored_as_colour;
    ASSERT_EQ(out["warnings"].size(), 1U) << out.dump(1);
    EXPECT_EQ(out["warnings"][0]["code"], "no_colour");
    EXPECT_NE(out["warnings"][0]["message"].get<std::string>().find("colour"), std::string::npos);
  }
}

/// The bytes of a base64 data URL of `media_type`, decoded by OpenSSL; empty when it is not one.
std::string DataUrlBytes(const std::string& url, const std::string& media_type) {
  const std::string prefix = "data:" + media_type + ";base64,";
  if (url.rfind(prefix, 0) != 0) return {};
  const std::string text = url.substr(prefix.size());
  if (text.size() % 4 != 0) return {};
  std::string bytes(text.size() / 4 * 3, '\0');
  const int n = EVP_DecodeBlock(reinterpret_cast<unsigned char*>(bytes.data()),
                                reinterpret_cast<const unsigned char*>(text.data()),
                                static_cast<int>(text.size()));
  if (n < 0) return {};
  const std::size_t padding = text.size() - text.find_last_not_of('=') - 1;
  bytes.resize(static_cast<std::size_t>(n) - padding);
  return bytes;
}

cv::Mat Decode(const std::string& bytes) {
  return cv::imdecode(std::vector<std::uint8_t>(bytes.begin(), bytes.end()), cv::IMREAD_COLOR);
}

// ?overlay=inline: one upload answers the usual JSON and the outlined photo, as a data URL; a
// client that shows both (the scanner page's use case) need not send the photo twice.
TEST_F(ServeTest, DetectOverlayInlineGivesTheJsonAndTheOutlinedPhotoFromOneUpload) {
  const Photo photo = PhotographLabel(client(), counter(), "110001", 30);
  ASSERT_FALSE(photo.jpeg.empty());
  const httplib::MultipartFormDataItems form = {{"image", photo.jpeg, "photo.jpg", "image/jpeg"}};
  json plain = ExpectJson(client().Post("/api/v1/detect", scanner(), form));
  json inline_answer = ExpectJson(client().Post("/api/v1/detect?overlay=inline", scanner(), form));

  // The JSON is the plain answer plus "overlay" (times differ from call to call).
  ASSERT_TRUE(inline_answer.contains("overlay"));
  const std::string url = inline_answer["overlay"];
  inline_answer.erase("overlay");
  inline_answer.erase("time_ms");
  plain.erase("time_ms");
  EXPECT_EQ(inline_answer, plain);
  ASSERT_EQ(plain["tags"].size(), 1U);
  EXPECT_EQ(plain["tags"][0]["pincode"], "110001");

  // The data URL holds the same PNG ?overlay=1 answers, at the photo's size.
  const std::string png = DataUrlBytes(url, "image/png");
  ASSERT_FALSE(png.empty()) << url.substr(0, 80);
  auto r = client().Post("/api/v1/detect?overlay=1", scanner(), form);
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200);
  EXPECT_TRUE(png == r->body) << "inline " << png.size() << " bytes, ?overlay=1 " << r->body.size();
  const cv::Mat overlay = Decode(png);
  const cv::Mat uploaded = Decode(photo.jpeg);
  ASSERT_EQ(overlay.size(), uploaded.size());
  // The outline is drawn on the tag's edges; far from the tag the photo is untouched.
  cv::Mat difference;
  cv::absdiff(overlay, uploaded, difference);
  const auto changed = [&](cv::Point2d p) {
    const cv::Vec3b d = difference.at<cv::Vec3b>(cvRound(p.y), cvRound(p.x));
    return std::max({d[0], d[1], d[2]});
  };
  for (int c = 0; c < 4; ++c) {
    const cv::Point2d mid = (photo.truth.corners_px[c] + photo.truth.corners_px[(c + 1) % 4]) / 2;
    EXPECT_GT(changed(mid), 60) << "edge " << c;
  }
  EXPECT_EQ(changed({1900, 1060}), 0);

  // One scan-log row per upload, and the log keeps what was read, not the picture.
  ScanRowsOnceThereAre(db_path_, 3);
  auto opened = db::OpenDatabase(db_path_, {.create = false});
  ASSERT_TRUE(opened);
  auto scans = db::RecentScans(opened.value().connection, 10);
  ASSERT_TRUE(scans);
  ASSERT_EQ(scans->size(), 3U);
  const json logged = json::parse((*scans)[1].result_json);
  EXPECT_EQ(logged["tags"][0]["pincode"], "110001");
  EXPECT_FALSE(logged.contains("overlay"));
}

// Three tags in one photo: an active pincode, a retired one (its printed labels still decode) and a
// key no pincode holds (reported as such, never mapped to a guess).
TEST_F(ServeTest, EveryTagInAFrameActiveRetiredAndUnknownKeys) {
  const int free_key = freeKey();
  ASSERT_GE(free_key, 0);
  const json retired =
      ExpectJson(client().Post("/api/v1/pincodes/560001/retire", admin(), "", "text/plain"));
  const int retired_key = retired["key"];
  scene::SceneSpec spec;
  spec.seed = 3;
  const std::vector<std::pair<int, cv::Point2d>> tags = {
      {11684, {420, 540}}, {retired_key, {960, 540}}, {free_key, {1500, 540}}};
  for (const auto& [key, at] : tags) {
    scene::PlacedMarker marker;
    marker.texture = scene::PinTagTexture(key, 256);
    marker.pose =
        scene::MakePose(spec.camera, at, scene::DistanceForSquarePx(spec.camera, 180), 20, 45, 10);
    spec.markers.push_back(marker);
  }
  std::vector<std::uint8_t> png;
  cv::imencode(".png", scene::RenderScene(spec).bgr, png);
  const json out = ExpectJson(
      client().Post("/api/v1/detect", scanner(), std::string(png.begin(), png.end()), "image/png"));
  ASSERT_EQ(out["tags"].size(), 3U) << out.dump(1);
  EXPECT_EQ(out["image"]["chroma_upsampling"], "none");  // a PNG's colour is whole
  std::map<int, json> by_key;
  for (const json& tag : out["tags"]) by_key[tag["key"].get<int>()] = tag;
  ASSERT_EQ(by_key.size(), 3U);
  EXPECT_EQ(by_key[11684]["pincode"], "110001");
  EXPECT_EQ(by_key[11684]["status"], "active");
  EXPECT_EQ(by_key[11684]["bin"], "11");
  EXPECT_EQ(by_key[retired_key]["pincode"], "560001");
  EXPECT_EQ(by_key[retired_key]["status"], "retired");
  EXPECT_EQ(by_key[retired_key]["bin"], "56");
  const json& unknown = by_key[free_key];
  EXPECT_EQ(unknown["status"], "unknown_key");
  EXPECT_TRUE(unknown["pincode"].is_null());
  EXPECT_TRUE(unknown["bin"].is_null());
  EXPECT_TRUE(unknown["office"].is_null());
  EXPECT_TRUE(unknown["district"].is_null());
  EXPECT_TRUE(unknown.contains("pose"));
  EXPECT_TRUE(unknown.contains("corners_px"));

  // Both counters are incremented inside the handler, before its response was sent.
  const std::string metrics = client().Get("/metrics")->body;
  EXPECT_NE(metrics.find("pintag_detections_total 3"), std::string::npos);
  EXPECT_NE(metrics.find("pintag_detections_unknown_key_total 1"), std::string::npos);
}

// A mirrored photo of a tag whose mirror image is another pincode's tag reads as that pincode
// (the format cannot tell them apart); both answers name the other pincode, so a scanner that
// may mirror its photos can send the parcel to be sorted by hand.
TEST_F(ServeTest, ATagWhoseMirrorImageIsAnotherPincodesNamesIt) {
  const int key = ExpectJson(client().Get("/api/v1/pincodes/609405"))["key"];
  const auto mirror = MirrorImageKey(TagKey(static_cast<std::uint16_t>(key)));
  ASSERT_TRUE(mirror.has_value()) << "609405's key " << key << " has no valid mirror image";
  const json other = ExpectJson(client().Get("/api/v1/keys/" + std::to_string(mirror->value())));
  const std::string other_pincode = other["pincode"];

  const auto label = client().Get("/api/v1/labels/609405.png?dpi=150", counter());
  ASSERT_TRUE(label && label->status == 200);
  const cv::Mat photo = Decode(label->body);
  cv::Mat flipped;
  cv::flip(photo, flipped, 1);
  const auto detect = [&](const cv::Mat& image) {
    std::vector<std::uint8_t> png;
    cv::imencode(".png", image, png);
    const json out = ExpectJson(client().Post("/api/v1/detect", scanner(),
                                              std::string(png.begin(), png.end()), "image/png"));
    EXPECT_EQ(out["tags"].size(), 1U) << out.dump(1);
    return out["tags"].empty() ? json() : out["tags"][0];
  };
  const json upright = detect(photo);
  EXPECT_EQ(upright["pincode"], "609405");
  EXPECT_EQ(upright["mirror_key"], mirror->value());
  EXPECT_EQ(upright["mirror_pincode"], other_pincode);
  const json mirrored = detect(flipped);
  EXPECT_EQ(mirrored["pincode"], other_pincode);
  EXPECT_EQ(mirrored["mirror_key"], key);
  EXPECT_EQ(mirrored["mirror_pincode"], "609405");

  // A key whose mirror image is no tag names none: 110001's (its mirror fails the parity).
  ASSERT_FALSE(MirrorImageKey(TagKey(11684)).has_value());
  const auto plain_label = client().Get("/api/v1/labels/110001.png?dpi=150", counter());
  ASSERT_TRUE(plain_label && plain_label->status == 200);
  const json plain = detect(Decode(plain_label->body));
  EXPECT_EQ(plain["pincode"], "110001");
  EXPECT_TRUE(plain["mirror_key"].is_null());
  EXPECT_TRUE(plain["mirror_pincode"].is_null());
}

// A phone photo carries its focal length in EXIF: pose then uses it ("exif"), not a guess.
TEST_F(ServeTest, ExifFocalLengthGivesTheIntrinsics) {
  scene::SceneSpec spec;
  scene::PlacedMarker marker;
  marker.texture = scene::PinTagTexture(11684, 256);
  marker.pose = scene::MakePose(spec.camera, {960, 540},
                                scene::DistanceForSquarePx(spec.camera, 200), 20, 0, 0);
  spec.markers.push_back(marker);
  const cv::Mat bgr = scene::RenderScene(spec).bgr;
  cv::Mat rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  const std::string path = dir_.file("phone.jpg");
  {
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out);
    OIIO::ImageSpec image_spec(rgb.cols, rgb.rows, 3, OIIO::TypeDesc::UINT8);
    image_spec.attribute("Exif:FocalLengthIn35mmFilm", 28);
    image_spec.attribute("Compression", "jpeg:92");
    ASSERT_TRUE(out->open(path, image_spec));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, rgb.data));
    out->close();
  }
  const json out = ExpectJson(
      client().Post("/api/v1/detect?tag_size_mm=50", scanner(), ReadFile(path), "image/jpeg"));
  EXPECT_EQ(out["intrinsics"]["source"], "exif");
  ASSERT_EQ(out["tags"].size(), 1U) << out.dump(1);
  EXPECT_EQ(out["tags"][0]["pincode"], "110001");
  // 28 mm equivalent: fx = 28 mm over the 35 mm frame's diagonal (43.27 mm), times the image's
  // diagonal in pixels (the detector's camera model).
  EXPECT_NEAR(out["intrinsics"]["fx"].get<double>(),
              28.0 * std::hypot(1920.0, 1080.0) / std::hypot(36.0, 24.0), 1.0);
}

std::uint32_t Crc(const std::string& bytes) {
  return static_cast<std::uint32_t>(
      crc32(0, reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(bytes.size())));
}

std::string Be32(std::uint32_t v) {
  return {static_cast<char>(v >> 24), static_cast<char>(v >> 16), static_cast<char>(v >> 8),
          static_cast<char>(v)};
}

std::string Chunk(const std::string& type, const std::string& data) {
  return Be32(static_cast<std::uint32_t>(data.size())) + type + data + Be32(Crc(type + data));
}

/// A well-formed, tiny PNG whose header claims width x height pixels.
std::string PngClaiming(std::uint32_t width, std::uint32_t height) {
  std::string ihdr = Be32(width) + Be32(height) + std::string("\x08\x02\x00\x00\x00", 5);
  std::string idat_raw(1000, '\0');
  uLongf size = compressBound(idat_raw.size());
  std::string idat(size, '\0');
  compress(reinterpret_cast<Bytef*>(idat.data()), &size,
           reinterpret_cast<const Bytef*>(idat_raw.data()), idat_raw.size());
  idat.resize(size);
  return std::string("\x89PNG\r\n\x1a\n", 8) + Chunk("IHDR", ihdr) + Chunk("IDAT", idat) +
         Chunk("IEND", "");
}

std::string SmallJpeg(int width = 64, int height = 48) {
  std::vector<std::uint8_t> jpeg;
  cv::imencode(".jpg", cv::Mat(height, width, CV_8UC3, cv::Scalar(30, 120, 200)), jpeg);
  return {jpeg.begin(), jpeg.end()};
}

/// A real small JPEG with its SOF0 size patched to width x height.
std::string JpegClaiming(std::uint16_t width, std::uint16_t height) {
  std::string jpeg = SmallJpeg();
  for (std::size_t i = 2; i + 9 < jpeg.size(); ++i) {
    if (static_cast<unsigned char>(jpeg[i]) == 0xFF &&
        static_cast<unsigned char>(jpeg[i + 1]) == 0xC0) {
      jpeg[i + 5] = static_cast<char>(height >> 8);
      jpeg[i + 6] = static_cast<char>(height & 0xFF);
      jpeg[i + 7] = static_cast<char>(width >> 8);
      jpeg[i + 8] = static_cast<char>(width & 0xFF);
      return jpeg;
    }
  }
  ADD_FAILURE() << "no SOF0 in the test JPEG";
  return jpeg;
}

TEST_F(ServeTest, DetectRefusesBadUploadsWithProblems) {
  const std::string jpeg = SmallJpeg();
  // Auth before anything: no token, a wrong one, a counter token.
  ExpectProblem(client().Post("/api/v1/detect", jpeg, "image/jpeg"), 401);
  ExpectProblem(client().Post("/api/v1/detect", Auth("pt_9_nope"), jpeg, "image/jpeg"), 401);
  ExpectProblem(client().Post("/api/v1/detect", counter(), jpeg, "image/jpeg"), 403);
  // A whole small JPEG with no tag: fine, no tags.
  EXPECT_EQ(
      ExpectJson(client().Post("/api/v1/detect", scanner(), jpeg, "image/jpeg"))["tags"].size(),
      0U);

  // Pixel bombs: tiny files whose headers claim 100000 x 100000 and 60000 x 60000 pixels.
  const std::string png_bomb = PngClaiming(100000, 100000);
  EXPECT_LT(png_bomb.size(), 2000U);
  json p = ExpectProblem(client().Post("/api/v1/detect", scanner(), png_bomb, "image/png"), 413);
  EXPECT_EQ(p["title"], "Image Too Large");
  EXPECT_NE(p["detail"].get<std::string>().find("100000 x 100000"), std::string::npos);
  EXPECT_NE(p["detail"].get<std::string>().find("lower resolution"), std::string::npos);
  ExpectProblem(
      client().Post("/api/v1/detect", scanner(), JpegClaiming(60000, 60000), "image/jpeg"), 413);
  httplib::MultipartFormDataItems bomb_form = {{"image", png_bomb, "bomb.png", "image/png"}};
  ExpectProblem(client().Post("/api/v1/detect", scanner(), bomb_form), 413);

  // Truncated JPEG and PNG: 400.
  EXPECT_EQ(ExpectProblem(client().Post("/api/v1/detect", scanner(),
                                        jpeg.substr(0, jpeg.size() / 2), "image/jpeg"),
                          400)["title"],
            "Corrupt Image");
  const std::string png = PngClaiming(64, 48);
  ExpectProblem(
      client().Post("/api/v1/detect", scanner(), png.substr(0, png.size() - 20), "image/png"), 400);
  // Bytes that are no image at all: 415; a body type the route does not take: 415; none: 400.
  ExpectProblem(client().Post("/api/v1/detect", scanner(), std::string(5000, 'x'), "image/jpeg"),
                415);
  ExpectProblem(client().Post("/api/v1/detect", scanner(), "%PDF-1.4 not an image",
                              "application/octet-stream"),
                415);
  ExpectProblem(client().Post("/api/v1/detect", scanner(), jpeg, "text/plain"), 415);
  ExpectProblem(client().Post("/api/v1/detect", scanner(), jpeg, "application/json"), 415);
  ExpectProblem(client().Post("/api/v1/detect", scanner(), "", "image/jpeg"), 400);
  httplib::MultipartFormDataItems wrong_field = {{"photo", jpeg, "a.jpg", "image/jpeg"}};
  json missing = ExpectProblem(client().Post("/api/v1/detect", scanner(), wrong_field), 400);
  EXPECT_EQ(missing["title"], "No Image");
  EXPECT_NE(missing["detail"].get<std::string>().find("its parts are named 'photo'"),
            std::string::npos)
      << missing;
  // A part whose name cpp-httplib does not read (the filename first): the answer says how a part
  // must be named, where it said only that no part was named 'image'.
  const std::string boundary = "b0undary";
  const std::string reordered =
      "--" + boundary +
      "\r\nContent-Disposition: form-data; filename=\"a.jpg\"; name=\"image\"\r\n"
      "Content-Type: image/jpeg\r\n\r\n" +
      jpeg + "\r\n--" + boundary + "--\r\n";
  missing = ExpectProblem(client().Post("/api/v1/detect", scanner(), reordered,
                                        "multipart/form-data; boundary=" + boundary),
                          400);
  EXPECT_EQ(missing["title"], "No Image");
  EXPECT_NE(missing["detail"].get<std::string>().find("with the name quoted and first"),
            std::string::npos)
      << missing;
  const httplib::MultipartFormDataItems empty_image = {{"image", "", "a.jpg", "image/jpeg"}};
  missing = ExpectProblem(client().Post("/api/v1/detect", scanner(), empty_image), 400);
  EXPECT_EQ(missing["title"], "No Image");
  EXPECT_NE(missing["detail"].get<std::string>().find("the part named 'image' is empty"),
            std::string::npos)
      << missing;
  // Query parameters.
  ExpectProblem(client().Post("/api/v1/detect?tag_size_mm=0", scanner(), jpeg, "image/jpeg"), 400);
  ExpectProblem(client().Post("/api/v1/detect?fx=1000", scanner(), jpeg, "image/jpeg"), 400);
  ExpectProblem(client().Post("/api/v1/detect?fx=abc&fy=1", scanner(), jpeg, "image/jpeg"), 400);
  ExpectProblem(client().Post("/api/v1/detect?overlay=maybe", scanner(), jpeg, "image/jpeg"), 400);
  EXPECT_EQ(ExpectProblem(client().Post("/api/v1/detect?plan=nope", scanner(), jpeg, "image/jpeg"),
                          404)["title"],
            "Unknown Sort Plan");
  // GET is not how one detects.
  ExpectProblem(client().Get("/api/v1/detect", scanner()), 405);

  // Refused photos are in the scan log too (with the problem); refused tokens are not.
  ScanRowsOnceThereAre(db_path_, 13);
  auto opened = db::OpenDatabase(db_path_, {.create = false});
  ASSERT_TRUE(opened);
  auto scans = db::RecentScans(opened.value().connection, 100);
  ASSERT_TRUE(scans);
  EXPECT_EQ(scans->size(), 13U);  // every POST above that reached the handler with a photo
  bool bomb_logged = false;
  for (const db::ScanRecord& scan : *scans) {
    const json result = json::parse(scan.result_json);
    if (result.contains("error") && result["error"]["status"] == 413 &&
        scan.image_width == 100000) {
      bomb_logged = true;
    }
  }
  EXPECT_TRUE(bomb_logged);
}

// A query is split as a browser splits it: a value runs from its name's first '=' to the next
// '&'. cpp-httplib kept the part after a value's last '=' (fx=1000=2000 read as 2000, a plan
// named "nope=default" as the default plan) and let two identical pieces through as one.
TEST_F(ServeTest, AQueryValueHoldingAnEqualsSignOrAParameterGivenTwiceIsRefused) {
  const std::string jpeg = SmallJpeg();
  const auto post = [&](const std::string& query) {
    return client().Post("/api/v1/detect?" + query, scanner(), jpeg, "image/jpeg");
  };
  json problem = ExpectProblem(post("fx=1000=2000&fy=1000"), 400);
  EXPECT_NE(problem["detail"].get<std::string>().find("fx"), std::string::npos) << problem;
  problem = ExpectProblem(post("plan=nope=default"), 404);
  EXPECT_NE(problem["detail"].get<std::string>().find("nope=default"), std::string::npos)
      << problem;
  problem = ExpectProblem(post("overlay=1=0"), 400);
  EXPECT_NE(problem["detail"].get<std::string>().find("overlay"), std::string::npos) << problem;
  problem = ExpectProblem(post("fx=1000&fx=1000&fy=1000"), 400);
  EXPECT_EQ(problem["detail"], "the query parameter 'fx' is given 2 times; give it once");
  // Escaped, '=' and '&' are a value's own; empty pieces are nothing.
  problem = ExpectProblem(post("plan=a%3Db%26c"), 404);
  EXPECT_NE(problem["detail"].get<std::string>().find("a=b&c"), std::string::npos) << problem;
  const json read = ExpectJson(post("&fx=1000&&fy=1000&"));
  EXPECT_EQ(read["intrinsics"]["fx"], 1000.0);
  EXPECT_EQ(read["intrinsics"]["source"], "given");
}

/// Sends raw bytes; returns what the server answers before it closes or goes quiet for 2 s.
std::string Raw(int port, const std::string& request) {
  return test::SendRaw(port, request, 2, [](const std::string& out) {
    return out.find("\r\n\r\n") != std::string::npos && out.find('}') != std::string::npos;
  });
}

TEST_F(ServeTest, BodyAndPixelLimitsAreFlags) {
  // The default body limit, 25 MiB, from the declared length before a byte of the body is read.
  const std::string head = "POST /api/v1/detect HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer " +
                           scanner_token_ + "\r\nContent-Type: image/jpeg\r\nContent-Length: ";
  std::string answer =
      Raw(server_->port(), head + std::to_string(25 * 1024 * 1024 + 1) + "\r\n\r\n");
  EXPECT_EQ(answer.rfind("HTTP/1.1 413", 0), 0U) << answer.substr(0, 300);
  EXPECT_NE(answer.find("application/problem+json"), std::string::npos);

  // Smaller limits from the command line: a 60 KiB body over a 50 KiB limit, a 2 MP photo over a
  // 1 MP limit, a batch of 3 labels over a limit of 2.
  // Each 413 gives its limit as a number too, which the scanner page shrinks a photo by.
  startServer({"--max-body-mb", "0.05", "--max-pixels", "1000000", "--max-batch", "2"});
  json p = ExpectProblem(client().Post("/api/v1/detect", scanner(),
                                       std::string(std::size_t{60} * 1024, 'x'), "image/jpeg"),
                         413);
  EXPECT_EQ(p["max_body_bytes"], 52428) << p.dump();  // 0.05 MiB is 52,428.8 bytes
  const std::string photo = SmallJpeg(1920, 1080);
  ASSERT_LT(photo.size(), 50U * 1024);
  p = ExpectProblem(client().Post("/api/v1/detect", scanner(), photo, "image/jpeg"), 413);
  EXPECT_NE(p["detail"].get<std::string>().find("1920 x 1080"), std::string::npos);
  EXPECT_EQ(p["max_pixels"], 1000000) << p.dump();
  EXPECT_EQ(p["width"], 1920);
  EXPECT_EQ(p["height"], 1080);
  EXPECT_EQ(ExpectJson(client().Post("/api/v1/detect", scanner(), SmallJpeg(1000, 1000),
                                     "image/jpeg"))["image"]["width"],
            1000);
  p = ExpectProblem(
      client().Post("/api/v1/labels", counter(), R"({"pincodes": ["110001", "110001", "110001"]})",
                    "application/json"),
      413);
  EXPECT_EQ(p["max_batch"], 2) << p.dump();  // the counter page splits a batch by it
}

TEST_F(ServeTest, PhotosBeyondThePixelBudgetWaitTheirTurnAndAllAreRead) {
  // A budget of one 1080p photo: four scanners uploading at once are decoded one at a time, and
  // every upload is still answered, with its tag.
  startServer({"--max-pixels", "2073600", "--max-pixels-in-flight", "2073600"});
  const Photo photo = PhotographLabel(client(), counter(), "110001", 20);
  ASSERT_FALSE(photo.jpeg.empty());
  const std::string query = "/api/v1/detect?tag_size_mm=" + std::to_string(photo.square_mm);
  constexpr int kScanners = 4, kUploads = 3;
  const int read = CallsRightFromConcurrentClients(
      server_->port(), kScanners, kUploads, [&](httplib::Client& scanner_client) {
        const httplib::Result r = scanner_client.Post(query, scanner(), photo.jpeg, "image/jpeg");
        if (!r || r->status != 200) return false;
        const json out = json::parse(r->body);
        return out["tags"].size() == 1 && out["tags"][0]["pincode"] == "110001";
      });
  EXPECT_EQ(read, kScanners * kUploads);
  // Uploads that overlapped waited; the counter says how many did.
  EXPECT_GE(Metric(client().Get("/metrics")->body, "pintag_pixel_budget_waits_total"), 1.0);
}

// An overlay copies the photo, encodes it as PNG and, inline, as base64 inside the JSON: a review
// measured 465 MB more resident memory for a 40 MP photo with ?overlay=inline against 190 MB
// without, where the budget counted the same pixels. An overlay now holds twice the photo's.
TEST_F(ServeTest, AnOverlayHoldsTwiceThePhotosPixelsUnderTheBudget) {
  const std::string jpeg = SmallJpeg();
  const json plain = ExpectJson(client().Post("/api/v1/detect", scanner(), jpeg, "image/jpeg"));
  const double pixels =
      plain["image"]["width"].get<double>() * plain["image"]["height"].get<double>();
  const auto peak = [&] {
    return Metric(client().Get("/metrics")->body, "pintag_pixel_budget_peak_pixels");
  };
  EXPECT_EQ(peak(), pixels);
  EXPECT_EQ(Metric(client().Get("/metrics")->body, "pintag_pixel_budget_held_pixels"), 0);
  for (const char* overlay : {"inline", "1"}) {
    startServer();  // a fresh peak
    const auto r = client().Post(std::string("/api/v1/detect?overlay=") + overlay, scanner(), jpeg,
                                 "image/jpeg");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200) << overlay;
    EXPECT_EQ(peak(), 2 * pixels) << overlay;
  }
}

TEST_F(ServeTest, APixelBudgetBelowOnePhotoIsRefusedBeforeAnythingIsCreated) {
  const std::string db = dir_.file("never-made.db");
  const CommandResult refused = RunPintag("serve --port 0 --bind 127.0.0.1 --db " + db +
                                          " --max-pixels 1000000 --max-pixels-in-flight 999999");
  EXPECT_EQ(refused.status, 2) << refused.out;
  EXPECT_NE(refused.out.find("--max-pixels-in-flight 999999 is below --max-pixels 1000000"),
            std::string::npos)
      << refused.out;
  EXPECT_FALSE(std::filesystem::exists(db));
}

}  // namespace
}  // namespace pintag::serve_test
