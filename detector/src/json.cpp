#include "pintag/detector/json.hpp"

#include "pintag/codec/mirror.hpp"
#include "pintag/detector/detector.hpp"

namespace pintag {
namespace {

using nlohmann::json;

json Xy(const Point2& p) {
  return json::array({p.x, p.y});
}

json PoseJson(const PoseSolution& p) {
  return {{"rotation_matrix", p.rotation},   {"rotation_vector", p.rotation_vector},
          {"quaternion_wxyz", p.quaternion}, {"translation_m", p.translation},
          {"distance_m", p.distance_m},      {"reprojection_error_px", p.reprojection_error_px}};
}

/// The square's centre: tag point (0.5, 0.5) through the homography (not the corners' mean,
/// which perspective moves off the centre).
json CentreJson(const std::array<double, 9>& h) {
  const double w = h[6] * 0.5 + h[7] * 0.5 + h[8];
  if (w == 0) return nullptr;
  return json::array({(h[0] * 0.5 + h[1] * 0.5 + h[2]) / w, (h[3] * 0.5 + h[4] * 0.5 + h[5]) / w});
}

const char* BitName(Bit b) {
  return b == Bit::kOne ? "1" : b == Bit::kZero ? "0" : "?";
}

// The options' fields, named once for reading and writing.
template <typename Options, typename Visit>
void VisitOptions(Options& o, Visit&& visit) {
  visit("assumed_hfov_deg", o.assumed_hfov_deg);
  visit("tag_size_m", o.tag_size_m);
  visit("red_min_a", o.red_min_a);
  visit("red_min_b", o.red_min_b);
  visit("faint_red_min_a", o.faint_red_min_a);
  visit("min_bit_span_b", o.min_bit_span_b);
  visit("min_bit_margin", o.min_bit_margin);
  visit("min_element_area_px", o.min_element_area_px);
  visit("max_element_area_ratio", o.max_element_area_ratio);
  visit("min_square_px", o.min_square_px);
  visit("max_blobs", o.max_blobs);
  visit("faint_max_element_area_px", o.faint_max_element_area_px);
  visit("faint_min_blobs", o.faint_min_blobs);
  visit("faint_max_cluster_blobs", o.faint_max_cluster_blobs);
  visit("dark_square_candidates", o.dark_square_candidates);
  visit("max_model_reads", o.max_model_reads);
  visit("threads", o.threads);
  visit("debug_dir", o.debug_dir);
  visit("return_rejected", o.return_rejected);
}

}  // namespace

json ToJson(const Detection& d) {
  json j;
  j["key"] = d.key ? json(d.key->value()) : json(nullptr);
  // The key this tag reads as in a mirrored photo; the format cannot tell the two apart.
  std::optional<TagKey> mirror;
  if (d.key) mirror = MirrorImageKey(*d.key);
  j["mirror_key"] = mirror ? json(mirror->value()) : json(nullptr);
  if (!d.reject_reason.empty()) j["reject_reason"] = d.reject_reason;
  j["corners_px"] = json::array();
  j["element_centres_px"] = json::array();
  for (int i = 0; i < 4; ++i) {
    j["corners_px"].push_back(Xy(d.corners[i]));
    j["element_centres_px"].push_back(Xy(d.element_centres[i]));
  }
  j["elements_seen"] = d.element_seen;
  j["centre_px"] = CentreJson(d.homography);
  j["homography"] = d.homography;
  j["square_px"] = d.square_px;
  if (d.key) {
    j["pose"] = PoseJson(d.pose);
    j["alternative_pose"] = PoseJson(d.alternative_pose);
    j["pose_ambiguous"] = d.pose_ambiguous;
    j["intrinsics"] = std::string(ToString(d.intrinsics_source));
  }
  json bits = {{"green", json::array()}, {"red", json::array()}};
  json margins = {{"green", json::array()}, {"red", json::array()}};
  for (int e = 0; e < kElements; ++e) {
    std::string green, red;
    for (Bit b : d.cells.green[e]) green += BitName(b);
    for (Bit b : d.cells.red[e]) red += BitName(b);
    bits["green"].push_back(green);
    bits["red"].push_back(red);
    margins["green"].push_back(d.margins.green[e]);
    margins["red"].push_back(d.margins.red[e]);
  }
  j["bits"] = bits;
  j["bit_margins"] = margins;
  j["unknown_bits"] = d.unknown_bits;
  j["bits_from_second_copy"] = d.bits_from_second_copy;
  j["bit_from_parity"] = d.bit_from_parity;
  j["read_through_blur_model"] = d.read_through_blur_model;
  j["min_known_margin"] = d.min_known_margin;
  return j;
}

json ToJson(const std::vector<PhotoWarning>& warnings) {
  json out = json::array();
  for (const PhotoWarning& w : warnings) out.push_back({{"code", w.code}, {"message", w.message}});
  return out;
}

json ToJson(const DetectResult& r) {
  json j;
  j["detections"] = json::array();
  for (const Detection& d : r.detections) j["detections"].push_back(ToJson(d));
  j["intrinsics"] = {{"fx", r.intrinsics.fx},
                     {"fy", r.intrinsics.fy},
                     {"cx", r.intrinsics.cx},
                     {"cy", r.intrinsics.cy},
                     {"distortion", r.intrinsics.distortion}};
  j["intrinsics_source"] = std::string(ToString(r.intrinsics_source));
  const StageTimings& t = r.timings;
  j["timings_ms"] = {{"redness", t.redness_ms},     {"blobs", t.blobs_ms},
                     {"quads", t.quads_ms},         {"sample", t.sample_ms},
                     {"model_fit", t.model_fit_ms}, {"codeword", t.codeword_ms},
                     {"pose", t.pose_ms},           {"total", t.total_ms}};
  j["model_reads"] = {{"read", t.model_reads},
                      {"reread", t.model_rereads},
                      {"mosaic_reread", t.mosaic_rereads},
                      {"skipped_over_budget", t.model_skipped}};
  j["warnings"] = ToJson(r.warnings);
  if (!r.error.empty()) j["error"] = r.error;
  return j;
}

json ToJson(const DetectorOptions& options) {
  json j;
  VisitOptions(options, [&](const char* name, const auto& field) { j[name] = field; });
  if (options.intrinsics) {
    const CameraIntrinsics& c = *options.intrinsics;
    j["intrinsics"] = {
        {"fx", c.fx}, {"fy", c.fy}, {"cx", c.cx}, {"cy", c.cy}, {"distortion", c.distortion}};
  }
  return j;
}

bool OptionsFromJson(const json& j, DetectorOptions* options, std::string* error) {
  if (!j.is_object()) {
    *error = "options must be a JSON object";
    return false;
  }
  DetectorOptions out = *options;
  try {
    for (const auto& item : j.items()) {
      // Named references, not structured bindings: the lambda below captures them, which
      // clang 14 (clang-tidy's) does not allow for bindings.
      const std::string& name = item.key();
      const json& value = item.value();
      bool known = false;
      VisitOptions(out, [&](const char* field_name, auto& field) {
        if (name != field_name) return;
        known = true;
        field = value.get<std::decay_t<decltype(field)>>();
      });
      if (name == "intrinsics") {
        known = true;
        CameraIntrinsics c;
        c.fx = value.at("fx").get<double>();
        c.fy = value.at("fy").get<double>();
        c.cx = value.at("cx").get<double>();
        c.cy = value.at("cy").get<double>();
        if (value.contains("distortion")) {
          c.distortion = value["distortion"].get<std::vector<double>>();
        }
        out.intrinsics = c;
      }
      if (!known) {
        *error = "unknown option '" + name + "'";
        return false;
      }
    }
  } catch (const nlohmann::json::exception& e) {
    *error = std::string("bad option value: ") + e.what();
    return false;
  }
  *options = std::move(out);
  return true;
}

}  // namespace pintag
