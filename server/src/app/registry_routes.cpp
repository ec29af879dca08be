// Registry routes: pincode and key lookups, office search, adding and retiring pincodes.

#include <charconv>

#include "app/common.hpp"
#include "app/routes.hpp"
#include "pintag/db/sort_plan.hpp"

namespace pintag::app {
namespace {

HttpResponse GetPincode(const AppContext& context, const HttpRequest& request) {
  const Pincode pincode = ParsePincodeOrThrow(request.pathParam("pin"));
  auto connection = context.pool->acquire();
  return HttpResponse::Json(
      RecordJson(Unwrap(db::LookupPincode(*connection, pincode), "Unknown Pincode")).dump());
}

HttpResponse GetKey(const AppContext& context, const HttpRequest& request) {
  const std::string text = request.pathParam("key");
  int value = -1;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size() || !TagKey::IsValid(value)) {
    throw HttpError(400, "a key is an integer from 0 to 32767, got '" + text.substr(0, 40) + "'",
                    "Malformed Key");
  }
  auto connection = context.pool->acquire();
  auto record = db::LookupKey(*connection, TagKey(static_cast<std::uint16_t>(value)));
  if (!record && record.error().code == db::ErrorCode::kNotFound) {
    throw HttpError(404, "key " + text + " is not allocated to any pincode", "Unknown Key");
  }
  return HttpResponse::Json(RecordJson(Unwrap(std::move(record))).dump());
}

HttpResponse SearchPincodes(const AppContext& context, const HttpRequest& request) {
  db::SearchQuery query;
  query.name_prefix = request.queryParam("q").value_or("");
  query.district = request.queryParam("district").value_or("");
  query.state = request.queryParam("state").value_or("");
  if (query.name_prefix.empty() && query.district.empty() && query.state.empty()) {
    throw HttpError(400, "give at least one of q (office name prefix), district or state");
  }
  query.limit = static_cast<int>(IntQuery(request, "limit", 50, 1, 500));
  query.offset = static_cast<int>(IntQuery(request, "offset", 0, 0, 1'000'000'000));
  auto connection = context.pool->acquire();
  const db::SearchPage page = Unwrap(db::Search(*connection, query));
  json results = json::array();
  for (const db::OfficeHit& hit : page.hits) {
    results.push_back({{"pincode", hit.pincode.str()},
                       {"key", hit.key.value()},
                       {"status", db::ToString(hit.status)},
                       {"office", OfficeJson(hit.office, hit.pincode)}});
  }
  return HttpResponse::Json(json{
      {"total", page.total},
      {"limit", page.limit},
      {"offset", page.offset},
      {"results",
       std::move(results)}}.dump());
}

std::string Field(const json& object, const char* name, bool required) {
  if (!object.contains(name) || object[name].is_null()) {
    if (required) throw HttpError(400, std::string("office field '") + name + "' is required");
    return {};
  }
  if (!object[name].is_string())
    throw HttpError(400, std::string("office field '") + name + "' must be a string");
  return object[name].get<std::string>();
}

HttpResponse AddPincodeRoute(const AppContext& context, const HttpRequest& request) {
  const json body = JsonBody(request);
  if (!body.is_object() || !body.contains("pincode"))
    throw HttpError(400, R"(expected {"pincode": "NNNNNN", "offices": [{"name": …}, …]})");
  const json& pin = body["pincode"];
  std::string text;
  if (pin.is_string()) {
    text = pin.get<std::string>();
  } else if (pin.is_number_unsigned()) {
    text = std::to_string(pin.get<std::uint64_t>());
  } else {
    throw HttpError(400, "'pincode' must be a string of six digits", "Malformed Pincode");
  }
  const Pincode pincode = ParsePincodeOrThrow(text);
  std::vector<db::PostOffice> offices;
  if (body.contains("offices")) {
    if (!body["offices"].is_array()) throw HttpError(400, "'offices' must be a list");
    if (body["offices"].size() > 1000) throw HttpError(413, "at most 1000 offices per pincode");
    for (const json& o : body["offices"]) {
      if (!o.is_object()) throw HttpError(400, "each office must be an object");
      db::PostOffice office;
      office.name = Field(o, "name", true);
      office.district = Field(o, "district", true);
      office.state = Field(o, "state", true);
      office.circle = Field(o, "circle", false);
      office.region = Field(o, "region", false);
      office.division = Field(o, "division", false);
      if (auto v = Field(o, "branch_type", false); !v.empty()) office.branch_type = v;
      if (auto v = Field(o, "delivery", false); !v.empty()) office.delivery = v;
      if (auto v = Field(o, "taluk", false); !v.empty()) office.taluk = v;
      offices.push_back(std::move(office));
    }
  }
  auto connection = context.pool->acquire();
  auto added = db::AddPincode(*connection, pincode, offices);
  if (!added && added.error().code == db::ErrorCode::kConflict) {
    throw HttpError(409, added.error().message, "Pincode Exists");
  }
  HttpResponse response = HttpResponse::Json(RecordJson(Unwrap(std::move(added))).dump(), 201);
  response.headers.emplace_back("Location", "/api/v1/pincodes/" + pincode.str());
  return response;
}

HttpResponse RetirePincodeRoute(const AppContext& context, const HttpRequest& request) {
  const Pincode pincode = ParsePincodeOrThrow(request.pathParam("pin"));
  auto connection = context.pool->acquire();
  return HttpResponse::Json(
      RecordJson(Unwrap(db::RetirePincode(*connection, pincode), "Unknown Pincode")).dump());
}

}  // namespace

void AddRegistryRoutes(server::Router& router, const std::shared_ptr<const AppContext>& context) {
  router.add(MakeRoute("GET", "/api/v1/pincodes/{pin}", Access::kOpen, Bind(context, GetPincode),
                       "A pincode: key, status, district, state, circle, region, division and "
                       "every post office",
                       "registry"));
  Route search = MakeRoute("GET", "/api/v1/pincodes", Access::kOpen, Bind(context, SearchPincodes),
                           "Search post offices by name prefix, district and/or state", "registry");
  search.query = {{"q", "office name prefix (case-insensitive for ASCII)"},
                  {"district", "district, exact (case-insensitive for ASCII)"},
                  {"state", "state, exact (case-insensitive for ASCII)"},
                  {"limit", "page size, 1 to 500 (default 50)", "integer"},
                  {"offset", "rows to skip (default 0)", "integer"}};
  router.add(std::move(search));
  router.add(MakeRoute("GET", "/api/v1/keys/{key}", Access::kOpen, Bind(context, GetKey),
                       "The pincode a tag key belongs to (retired ones included)", "registry"));
  Route add = MakeRoute("POST", "/api/v1/pincodes", Access::kAdmin, Bind(context, AddPincodeRoute),
                        R"(Add a pincode (and its offices); answers 201 with the allocated key)",
                        "registry");
  add.consumes = {"application/json"};
  router.add(std::move(add));
  router.add(MakeRoute(
      "POST", "/api/v1/pincodes/{pin}/retire", Access::kAdmin, Bind(context, RetirePincodeRoute),
      "Retire a pincode: it keeps its key, labels are no longer issued", "registry"));
}

server::LabelContentProvider RegistryLabelProvider(
    const std::shared_ptr<const AppContext>& context) {
  return [context](Pincode pincode, const std::optional<std::string>& plan) -> server::LabelLookup {
    auto connection = context->pool->acquire();
    auto record = db::LookupPincode(*connection, pincode);
    if (!record) {
      if (record.error().code == db::ErrorCode::kNotFound) {
        return {
            std::nullopt,
            server::Problem{404, "Unknown Pincode",
                            "pincode " + pincode.str() + " is not in the registry", "about:blank"}};
      }
      ThrowDbError(record.error());
    }
    if (record->status == db::PincodeStatus::kRetired) {
      return {std::nullopt,
              server::Problem{410, "Retired Pincode",
                              "pincode " + pincode.str() + " was retired" +
                                  (record->retired_at ? " on " + *record->retired_at : "") +
                                  "; no new labels are issued for it (printed labels still decode)",
                              "about:blank"}};
    }
    LabelContent label;
    label.pincode = pincode;
    label.key = record->key;
    if (const db::PostOffice* office = MainOffice(*record)) label.office = office->name;
    label.district = record->district;
    label.state = record->state;
    if (plan) {
      auto found = db::GetPlan(*connection, *plan);
      if (!found) {
        if (found.error().code == db::ErrorCode::kNotFound) {
          return {std::nullopt,
                  server::Problem{404, "Unknown Sort Plan", "no sort plan named '" + *plan + "'",
                                  "about:blank"}};
        }
        ThrowDbError(found.error());
      }
      label.plan = plan;
      label.bin = db::RouteWith(*found, pincode).bin;
    }
    return {std::move(label), std::nullopt};
  };
}

}  // namespace pintag::app
