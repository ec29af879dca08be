// POST /api/v1/detect: photo bytes -> loader (format, pixel limit and whole file from the header,
// then decode, EXIF) -> Detector -> keys -> registry (pincode, status, office) -> sort plan (bin)
// -> JSON (the detector's form of each tag, with what the registry says); on request with the photo
// annotated, as PNG instead of the JSON (?overlay=1) or inside it as a data URL (?overlay=inline).
// Every call that reaches the handler is written to the scan log, refusals of the photo included.

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>

#include "app/data_url.hpp"
#include "app/db_problems.hpp"
#include "app/params.hpp"
#include "app/registry_json.hpp"
#include "app/routes.hpp"
#include "pintag/codec/label.hpp"
#include "pintag/codec/mirror.hpp"
#include "pintag/db/scan_log.hpp"
#include "pintag/db/snapshot.hpp"
#include "pintag/db/sort_plan.hpp"
#include "pintag/db/text.hpp"
#include "pintag/detector/detector.hpp"
#include "pintag/detector/json.hpp"
#include "pintag/detector/tag_outline.hpp"
#include "pintag/server/log.hpp"

namespace pintag::app {
namespace {

using Clock = std::chrono::steady_clock;

double Ms(Clock::time_point since) {
  return std::chrono::duration<double, std::milli>(Clock::now() - since).count();
}

/// What one decoded tag resolves to in the registry and the plan.
struct Resolved {
  std::optional<db::PincodeRecord> record;
  std::optional<db::Routing> routing;
  /// The pincode holding the key the tag reads as when the photo is mirrored, if one does.
  std::optional<Pincode> mirror_pincode;
};

/// The detector's JSON of the tag (the CLI prints the same), with what the registry and the plan
/// say about its key.
json TagJson(const Detection& d, const Resolved& r) {
  json tag = ToJson(d);
  if (r.record) {
    const db::PostOffice* office = db::MainOffice(*r.record);
    tag["pincode"] = r.record->pincode.str();
    tag["status"] = db::ToString(r.record->status);
    tag["office"] = office ? json(office->name) : json(nullptr);
    tag["district"] = r.record->district;
    tag["state"] = r.record->state;
    tag["bin"] = r.routing ? json(r.routing->bin) : json(nullptr);
  } else {
    // Never a guess: a key no pincode holds is reported as such, without pincode or bin.
    tag["pincode"] = nullptr;
    tag["status"] = "unknown_key";
    tag["office"] = nullptr;
    tag["district"] = nullptr;
    tag["state"] = nullptr;
    tag["bin"] = nullptr;
  }
  tag["mirror_pincode"] = r.mirror_pincode ? json(r.mirror_pincode->str()) : json(nullptr);
  return tag;
}

std::string OverlayPng(cv::Mat image, const DetectResult& result,
                       const std::vector<Resolved>& resolved) {
  for (std::size_t i = 0; i < result.detections.size(); ++i) {
    const Detection& d = result.detections[i];
    const bool known = resolved[i].record.has_value();
    std::string caption = known ? resolved[i].record->pincode.str()
                                : "key " + std::to_string(d.key->value()) + " unknown";
    if (known && resolved[i].routing) caption += "  bin " + resolved[i].routing->bin;
    char distance[32];
    std::snprintf(distance, sizeof distance, "  %.2f m", d.pose.distance_m);
    caption += distance;
    DrawTagOutline(image, d, known ? cv::Scalar(0, 220, 255) : cv::Scalar(0, 0, 255), caption);
  }
  std::vector<std::uint8_t> png;
  if (!cv::imencode(".png", image, png)) throw std::runtime_error("cannot encode the overlay");
  return {png.begin(), png.end()};
}

/// ?overlay=: the photo with the tags outlined, instead of the JSON or inside it.
enum class Overlay {
  kNone,    ///< absent, 0, false, no: the JSON alone
  kPng,     ///< 1, true, yes (or empty): the PNG instead of the JSON, as before there was kInline
  kInline,  ///< inline: the JSON with "overlay", the PNG as a data: URL (one upload, both)
};

Overlay OverlayQuery(const HttpRequest& request) {
  const std::optional<std::string> text = request.queryParam("overlay");
  if (!text || *text == "0" || *text == "false" || *text == "no") return Overlay::kNone;
  if (*text == "1" || *text == "true" || *text == "yes" || text->empty()) return Overlay::kPng;
  if (*text == "inline") return Overlay::kInline;
  throw HttpError(400,
                  "query parameter 'overlay' must be 1 (the outlined photo as PNG), inline (the "
                  "JSON with the outlined photo as a data URL) or 0");
}

/// What the scan log keeps of one call.
struct Outcome {
  std::string result_json;  ///< what was read, or the problem that ended the call
  std::optional<int> width, height;
};

void Log(const AppContext& context, const HttpRequest& request, std::size_t bytes,
         const Outcome& outcome) {
  context.metrics->increment(kScansCounter);
  db::ScanRecord scan;
  if (request.principal) {
    std::int64_t id = 0;
    const std::string& text = request.principal->id;
    if (std::from_chars(text.data(), text.data() + text.size(), id).ec == std::errc())
      scan.token_id = id;
  }
  scan.image_bytes = static_cast<std::int64_t>(bytes);
  scan.image_width = outcome.width;
  scan.image_height = outcome.height;
  scan.result_json = outcome.result_json;
  // The answer stands when the log cannot be written: the writer counts the scans it loses.
  context.scan_log->append(std::move(scan), request.request_id);
}

/// The answer `out` as the scan log keeps it. A row holds at most db::kMaxJsonBytes, which an
/// answer of about 330 tags passes (each tag's pose and corners take about 3 KB): past that each
/// tag keeps what was read and where (key, pincode, status, bin, centre), and past that again the
/// tags that fit, the rest counted in "tags_omitted". A row that says so beats a lost one.
/// `whole` is `out` as dumped.
std::string ScanLogJson(const json& out, const std::string& whole) {
  if (whole.size() <= db::kMaxJsonBytes) return whole;
  json abridged = out;
  abridged["scan_log_abridged"] = true;
  abridged["tags"] = json::array();
  json tags = json::array();
  const std::string head = abridged.dump();
  std::size_t room = db::kMaxJsonBytes - std::min(db::kMaxJsonBytes, head.size() + 64);
  std::size_t omitted = 0;
  for (const json& tag : out["tags"]) {
    json kept;
    for (const char* field : {"key", "pincode", "status", "bin", "centre_px"}) {
      if (tag.contains(field)) kept[field] = tag[field];
    }
    const std::size_t size = kept.dump().size() + 1;
    if (omitted == 0 && size <= room) {
      room -= size;
      tags.push_back(std::move(kept));
    } else {
      ++omitted;
    }
  }
  abridged["tags"] = std::move(tags);
  if (omitted > 0) abridged["tags_omitted"] = omitted;
  return abridged.dump();
}

HttpResponse Detect(const AppContext& context, const HttpRequest& request, std::string_view bytes,
                    Clock::time_point start, Outcome* outcome) {
  const std::string plan_name = PlanQuery(request);
  // By default the tag is the one printed on the default label (100 x 150 mm: 57.9 mm).
  const double tag_size_mm = NumberQuery(request, "tag_size_mm", 1, 10000)
                                 .value_or(TagPlacement(kLabel100x150).square_side_mm);
  const std::optional<double> fx = NumberQuery(request, "fx", 1e-3, 1e7);
  const std::optional<double> fy = NumberQuery(request, "fy", 1e-3, 1e7);
  const std::optional<double> cx = NumberQuery(request, "cx", -1e6, 1e6);
  const std::optional<double> cy = NumberQuery(request, "cy", -1e6, 1e6);
  if (fx.has_value() != fy.has_value()) throw HttpError(400, "give both fx and fy, or neither");
  if ((cx || cy) && !fx) throw HttpError(400, "cx and cy need fx and fy");
  const Overlay overlay = OverlayQuery(request);

  {
    // An unknown plan is refused before the photo costs a decode; each tag is routed after.
    auto connection = context.pool->acquire();
    RequirePlan(*connection, plan_name);
  }

  // The loader tells the format from the first bytes, checks the header's size against the pixel
  // limit before decoding and refuses truncated files; its error kind is the HTTP status.
  const std::span<const std::uint8_t> data(reinterpret_cast<const std::uint8_t*>(bytes.data()),
                                           bytes.size());
  // The photo's pixels are held from just before decoding until the answer is built (the
  // overlay too): decoded photos and the detector's buffers are most of a server's memory. An
  // overlay holds twice as many: its copy of the photo, the PNG, and for inline its base64 and
  // the JSON around it (a 40 MP JPEG, measured by a review: 190 MB more resident memory for the
  // JSON alone, 465 MB with ?overlay=inline, where the budget counts about 7 bytes a pixel).
  const std::int64_t budget_per_pixel = overlay == Overlay::kNone ? 1 : 2;
  PixelBudget::Reservation pixels;
  LoadOptions load_options;
  load_options.max_pixels = context.max_pixels;
  load_options.before_decode = [&](int width, int height) {
    pixels = {};  // never hold twice while waiting
    pixels = HoldPixels(context, std::int64_t{width} * height * budget_per_pixel);
  };
  const Clock::time_point decode_start = Clock::now();
  const LoadResult loaded = LoadImageBytes(data, load_options);
  if (loaded.claimed_width > 0) {
    outcome->width = loaded.claimed_width;
    outcome->height = loaded.claimed_height;
  }
  switch (loaded.kind) {
    case ImageError::kNone:
      break;
    case ImageError::kUnsupported:
      // Not a JPEG, PNG, TIFF or WebP, or one no photo is (more than four channels).
      throw HttpError(415, loaded.error, "Unsupported Image Format");
    case ImageError::kTooLarge: {
      // A phone's full-resolution photo is the usual cause: say what the scanner can change, and
      // give the numbers, so that a client (the scanner page) can shrink the photo to fit.
      server::Problem problem{
          413, "Image Too Large",
          loaded.error + ": set the camera to a lower resolution and take it again"};
      // Only for a photo over the pixel limit: a TIFF refused for its tiles' size would not be
      // let in by shrinking it to these.
      const std::int64_t claimed = std::int64_t{loaded.claimed_width} * loaded.claimed_height;
      if (claimed > context.max_pixels) {
        problem.numbers = {{"max_pixels", context.max_pixels},
                           {"width", loaded.claimed_width},
                           {"height", loaded.claimed_height}};
      }
      throw HttpError(std::move(problem));
    }
    case ImageError::kCorrupt:
    case ImageError::kUnreadable:
      throw HttpError(400, loaded.error, "Corrupt Image");
  }
  const double decode_ms = Ms(decode_start);
  const cv::Mat& image = loaded.image->bgr;
  outcome->width = image.cols;
  outcome->height = image.rows;

  DetectorOptions options;
  options.tag_size_m = tag_size_mm / 1000.0;
  if (fx) {
    options.intrinsics = CameraIntrinsics{
        *fx, *fy, cx.value_or((image.cols - 1) / 2.0), cy.value_or((image.rows - 1) / 2.0), {}};
  }
  const Clock::time_point detect_start = Clock::now();
  const DetectResult result = Detector(options).detect(*loaded.image);
  if (!result.error.empty()) throw HttpError(400, result.error, "Cannot Detect");
  const double detect_ms = Ms(detect_start);

  std::vector<Resolved> resolved;
  json tags = json::array();
  std::int64_t registry_version = 0;
  {
    auto connection = context.pool->acquire();
    // Every tag of the photo is resolved in one state of the registry, the one the answer names:
    // a sorter can tell an answer given before a plan's change (or by a replica behind it).
    const db::ReadTransaction one_state(*connection);
    db::Result<std::int64_t> version = db::RegistryVersion(*connection);
    if (!version) ThrowDbError(version.error());
    registry_version = *version;
    for (const Detection& d : result.detections) {
      Resolved r;
      if (d.key) {
        auto record = db::LookupKey(*connection, *d.key);
        if (record) {
          r.routing = RouteUnder(*connection, record->pincode, plan_name);
          r.record = std::move(record).value();
        } else if (record.error().code != db::ErrorCode::kNotFound) {
          ThrowDbError(record.error());
        }
        // A symmetric tag (64 keys) is its own mirror image: no other pincode to name.
        if (const std::optional<TagKey> mirror = MirrorImageKey(*d.key);
            mirror && *mirror != *d.key) {
          auto other = db::LookupKey(*connection, *mirror);
          if (other) {
            r.mirror_pincode = other->pincode;
          } else if (other.error().code != db::ErrorCode::kNotFound) {
            ThrowDbError(other.error());
          }
        }
        tags.push_back(TagJson(d, r));
      }
      resolved.push_back(std::move(r));
    }
  }
  context.metrics->increment(kDetectionsCounter, static_cast<double>(tags.size()));
  std::size_t unknown = 0;
  for (const json& tag : tags) unknown += tag["pincode"].is_null();
  if (unknown > 0) context.metrics->increment(kUnknownKeysCounter, static_cast<double>(unknown));

  json out;
  out["image"] = {{"width", image.cols},
                  {"height", image.rows},
                  {"format", loaded.image->format},
                  {"bytes", bytes.size()},
                  {"exif_orientation", loaded.image->exif_orientation},
                  {"chroma_upsampling", std::string(ToString(loaded.image->chroma_upsampling))}};
  out["intrinsics"] = {{"source", std::string(ToString(result.intrinsics_source))},
                       {"fx", result.intrinsics.fx},
                       {"fy", result.intrinsics.fy},
                       {"cx", result.intrinsics.cx},
                       {"cy", result.intrinsics.cy}};
  out["tag_size_mm"] = tag_size_mm;
  out["plan"] = plan_name;
  out["registry_version"] = registry_version;
  out["tag_count"] = tags.size();
  out["tags"] = std::move(tags);
  out["warnings"] = ToJson(result.warnings);
  out["time_ms"] = {{"decode", decode_ms}, {"detect", detect_ms}, {"total", Ms(start)}};
  // Dumped once: the answer as sent is the scan log's row, unless an overlay is added to it or
  // it is too long for a row.
  std::string body = out.dump();
  outcome->result_json = ScanLogJson(out, body);

  switch (overlay) {
    case Overlay::kNone:
      break;
    case Overlay::kPng: {
      HttpResponse response =
          HttpResponse::Bytes("image/png", OverlayPng(image.clone(), result, resolved));
      response.headers.emplace_back("X-PinTag-Tags", std::to_string(out["tag_count"].get<int>()));
      response.headers.emplace_back("X-PinTag-Registry-Version", std::to_string(registry_version));
      return response;
    }
    case Overlay::kInline:
      // Added after the scan log took its copy: the log keeps what was read, not the photo.
      out["overlay"] = DataUrl("image/png", OverlayPng(image.clone(), result, resolved));
      body = out.dump();
      break;
  }
  HttpResponse response = HttpResponse::Json(std::move(body));
  response.headers.emplace_back("X-PinTag-Registry-Version", std::to_string(registry_version));
  return response;
}

/// Why a multipart body has no photo, naming the parts it has. cpp-httplib 0.11.4 reads a part's
/// name only from `Content-Disposition: form-data; name="…"`, optionally followed by
/// `; filename="…"`; a part written otherwise (parameters in another order, a name unquoted)
/// comes with no name, and the client should be told that rather than that it sent no photo.
std::string NoImagePart(const HttpRequest& request) {
  std::string detail = "the multipart body needs a part named 'image'";
  if (request.parts.empty()) return detail + ", and it has no part";
  std::string names;
  bool unnamed = false;
  for (const server::FormPart& p : request.parts) {
    names += (names.empty() ? "'" : ", '") + p.name.substr(0, 64) + "'";
    unnamed = unnamed || p.name.empty();
  }
  detail += "; its parts are named " + names;
  if (unnamed) {
    detail +=
        ". A part's name is read only from a Content-Disposition of the form "
        "'form-data; name=\"image\"; filename=\"photo.jpg\"' (the filename optional), with the "
        "name quoted and first";
  }
  return detail;
}

}  // namespace

HttpResponse PostDetect(const AppContext& context, const HttpRequest& request) {
  const Clock::time_point start = Clock::now();
  std::string_view bytes = request.body;
  if (request.content_type == "multipart/form-data") {
    const server::FormPart* part = request.part("image");
    if (part == nullptr) throw HttpError(400, NoImagePart(request), "No Image");
    // One photo per call: reading the first of several would answer for photos never read.
    const auto images = std::count_if(request.parts.begin(), request.parts.end(),
                                      [](const server::FormPart& p) { return p.name == "image"; });
    if (images > 1) {
      throw HttpError(400, "the multipart body has " + std::to_string(images) +
                               " parts named 'image'; send one photo per request");
    }
    bytes = part->content;
    if (bytes.empty())
      throw HttpError(400, "no photo: the part named 'image' is empty", "No Image");
  }
  if (bytes.empty()) throw HttpError(400, "no photo: the body is empty", "No Image");
  Outcome outcome;
  try {
    HttpResponse response = Detect(context, request, bytes, start, &outcome);
    Log(context, request, bytes.size(), outcome);
    return response;
  } catch (const HttpError& e) {
    // The detail may quote the request's own bytes (a plan name, a parameter): not always UTF-8.
    outcome.result_json =
        json{{"error", {{"status", e.problem().status}, {"detail", e.problem().detail}}}}.dump(
            -1, ' ', false, json::error_handler_t::replace);
    Log(context, request, bytes.size(), outcome);
    throw;
  } catch (const std::exception& e) {
    // Unexpected (a decoder or OpenCV failure): the scan log still records the upload; the
    // message goes to the server log with the request id (InvokeHandler), not to the client.
    outcome.result_json =
        json{{"error",
              {{"status", 500}, {"detail", "unexpected failure: " + std::string(e.what())}}}}
            .dump(-1, ' ', false, json::error_handler_t::replace);
    Log(context, request, bytes.size(), outcome);
    throw;
  }
}

}  // namespace pintag::app
