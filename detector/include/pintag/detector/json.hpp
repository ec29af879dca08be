#pragma once
// JSON for detections (what the CLI and the HTTP API print) and for options (read and written from
// one list of field names, so the two can never drift apart).

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "pintag/detector/detection.hpp"
#include "pintag/detector/options.hpp"

namespace pintag {

nlohmann::json ToJson(const Detection& detection);
/// [{"code": "no_colour", "message": "..."}, ...]: DetectResult::warnings, as the CLI's JSON and
/// the detect route's answer both carry them.
nlohmann::json ToJson(const std::vector<PhotoWarning>& warnings);
/// {"detections": [...], "intrinsics": {...}, "intrinsics_source": "...", "timings_ms": {...},
///  "warnings": [...]}
nlohmann::json ToJson(const DetectResult& result);

nlohmann::json ToJson(const DetectorOptions& options);
/// Reads the fields present in `json` over `options`; unknown fields and wrong types are errors.
bool OptionsFromJson(const nlohmann::json& json, DetectorOptions* options, std::string* error);

}  // namespace pintag
