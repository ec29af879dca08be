// Registry routes: pincode and key lookups, office search, adding and retiring pincodes.

#include <algorithm>
#include <optional>

#include "app/db_problems.hpp"
#include "app/params.hpp"
#include "app/registry_json.hpp"
#include "app/routes.hpp"
#include "pintag/db/office_fields.hpp"
#include "pintag/db/text.hpp"

namespace pintag::app {
namespace {

// An office as GET /pincodes/{pin} writes it, so that one read can be posted back; any other
// field is refused rather than dropped (a misspelt "distrct" would lose the district).
constexpr const char* kRequiredFields[] = {"name",   "district", "state",
                                           "circle", "region",   "division"};
constexpr const char* kOptionalTextFields[] = {"branch_type", "delivery", "taluk"};
constexpr const char* kOtherFields[] = {"latitude", "longitude", "country", "pincode"};

bool Known(const std::string& field) {
  const auto in = [&](const auto& names) {
    return std::any_of(std::begin(names), std::end(names),
                       [&](const char* name) { return field == name; });
  };
  return in(kRequiredFields) || in(kOptionalTextFields) || in(kOtherFields);
}

std::optional<double> Degrees(const json& o, const char* name, const std::string& office) {
  if (!o.contains(name) || o[name].is_null()) return std::nullopt;
  if (!o[name].is_number()) throw HttpError(400, office + ": '" + name + "' must be a number");
  return o[name].get<double>();
}

db::PostOffice OfficeFromJson(const json& o, std::size_t index, Pincode pincode) {
  const std::string office = "office " + std::to_string(index + 1);
  if (!o.is_object()) throw HttpError(400, office + " must be an object");
  // Every unknown field and every missing or blank required one at once, so that a form can be
  // put right in one go.
  // At most 10 named, each cut to 40 bytes: the answer must not echo a body of junk keys whole.
  constexpr std::size_t kUnknownNamed = 10;
  std::string unknown;
  std::size_t unknown_count = 0;
  for (const auto& [field, value] : o.items()) {
    if (Known(field)) continue;
    if (++unknown_count <= kUnknownNamed) {
      unknown += (unknown.empty() ? "'" : ", '") + field.substr(0, 40) + "'";
    }
  }
  if (unknown_count > kUnknownNamed) {
    unknown += " and " + std::to_string(unknown_count - kUnknownNamed) + " more";
  }
  const auto text = [&](const char* name) -> std::optional<std::string> {
    if (!o.contains(name) || o[name].is_null()) return std::nullopt;
    if (!o[name].is_string()) throw HttpError(400, office + ": '" + name + "' must be a string");
    return o[name].get<std::string>();
  };
  std::string missing;
  for (const char* name : kRequiredFields) {
    const std::optional<std::string> value = text(name);
    if (!value || db::IsBlank(*value)) {  // spaces, U+00A0, U+200B, … only: nothing to read
      missing += (missing.empty() ? "" : ", ") + std::string(name);
    }
  }
  std::string problems;
  if (unknown_count > 0) {
    problems = office + (unknown_count == 1 ? ": unknown field " : ": unknown fields ") + unknown;
  }
  if (!missing.empty()) {
    problems += (problems.empty() ? "" : "; ") + office + " needs a non-empty " + missing +
                " (every office has name, district, state, circle, region and division)";
  }
  if (!problems.empty()) throw HttpError(400, problems);
  // As an import reads them: India Post's "NA" leaves an optional field unknown, and "B.O" is the
  // type BO (a head office typed "H.O" would not be the office a label prints).
  const auto optional_text = [&](const char* name) -> std::optional<std::string> {
    std::optional<std::string> value = text(name);
    if (value && db::MeansUnknown(db::TrimUnicodeSpaces(*value))) return std::nullopt;
    return value;
  };
  if (const auto country = text("country"); country && *country != "India") {
    throw HttpError(400, office + ": 'country' can only be India");
  }
  // Read as the body's own "pincode" is: six digits, as a string or a number.
  if (o.contains("pincode") && !o["pincode"].is_null()) {
    if (const Pincode own = PincodeValue(o["pincode"], office + ": 'pincode'"); own != pincode) {
      throw HttpError(400, office + ": 'pincode' " + own.str() + " is not the pincode being added");
    }
  }
  db::PostOffice result;
  result.name = *text("name");
  result.district = *text("district");
  result.state = *text("state");
  result.circle = *text("circle");
  result.region = *text("region");
  result.division = *text("division");
  result.branch_type = db::NormalizedOfficeType(optional_text("branch_type"));
  result.delivery = optional_text("delivery");
  result.taluk = optional_text("taluk");
  result.latitude = Degrees(o, "latitude", office);
  result.longitude = Degrees(o, "longitude", office);
  return result;
}

}  // namespace

HttpResponse GetPincode(const AppContext& context, const HttpRequest& request) {
  const Pincode pincode = PincodeParam(request);
  auto connection = context.pool->acquire();
  return HttpResponse::Json(
      RecordJson(Unwrap(db::LookupPincode(*connection, pincode), "Unknown Pincode")));
}

HttpResponse GetKey(const AppContext& context, const HttpRequest& request) {
  const TagKey key = KeyParam(request);
  auto connection = context.pool->acquire();
  auto record = db::LookupKey(*connection, key);
  if (!record && record.error().code == db::ErrorCode::kNotFound) {
    throw HttpError(404, "key " + std::to_string(key.value()) + " is not allocated to any pincode",
                    "Unknown Key");
  }
  return HttpResponse::Json(RecordJson(Unwrap(std::move(record))));
}

HttpResponse SearchPincodes(const AppContext& context, const HttpRequest& request) {
  db::SearchQuery query;
  query.name_prefix = request.queryParam("q").value_or("");
  query.district = request.queryParam("district").value_or("");
  query.state = request.queryParam("state").value_or("");
  if (query.name_prefix.empty() && query.district.empty() && query.state.empty()) {
    throw HttpError(400, "give at least one of q (office name prefix), district or state");
  }
  query.limit = static_cast<int>(IntegerQuery(request, "limit", 50, 1, 500));
  query.offset = static_cast<int>(IntegerQuery(request, "offset", 0, 0, 1'000'000'000));
  auto connection = context.pool->acquire();
  const db::SearchPage page = Unwrap(db::Search(*connection, query));
  return HttpResponse::Json(SearchPageJson(page));
}

HttpResponse PostPincode(const AppContext& context, const HttpRequest& request) {
  const json body = JsonBody(request);
  if (!body.is_object() || !body.contains("pincode"))
    throw HttpError(400, R"(expected {"pincode": "NNNNNN", "offices": [{"name": …}, …]})");
  if (const std::optional<std::string> field = UnknownField(body, {"pincode", "offices"})) {
    throw HttpError(400, "unknown field '" + *field +
                             "': a new pincode has 'pincode' and 'offices' only (its key is "
                             "allocated)");
  }
  const Pincode pincode = PincodeValue(body["pincode"], "'pincode'");
  std::vector<db::PostOffice> offices;
  if (body.contains("offices") && !body["offices"].is_null()) {
    if (!body["offices"].is_array()) throw HttpError(400, "'offices' must be a list");
    if (body["offices"].size() > 1000) throw HttpError(413, "at most 1000 offices per pincode");
    for (std::size_t i = 0; i < body["offices"].size(); ++i) {
      offices.push_back(OfficeFromJson(body["offices"][i], i, pincode));
    }
  }
  auto connection = context.pool->acquire();
  auto added = db::AddPincode(*connection, pincode, offices);
  if (!added && added.error().code == db::ErrorCode::kConflict) {
    throw HttpError(409, added.error().message, "Pincode Exists");
  }
  HttpResponse response = HttpResponse::Json(RecordJson(Unwrap(std::move(added))), 201);
  response.headers.emplace_back("Location", "/api/v1/pincodes/" + pincode.str());
  return response;
}

HttpResponse PostRetirePincode(const AppContext& context, const HttpRequest& request) {
  const Pincode pincode = PincodeParam(request);
  auto connection = context.pool->acquire();
  return HttpResponse::Json(
      RecordJson(Unwrap(db::RetirePincode(*connection, pincode), "Unknown Pincode")));
}

}  // namespace pintag::app
