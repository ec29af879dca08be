// Registry routes: pincode and key lookups, office search, adding and retiring pincodes.

#include "app/db_problems.hpp"
#include "app/params.hpp"
#include "app/registry_json.hpp"
#include "app/routes.hpp"

namespace pintag::app {
namespace {

std::string Field(const json& object, const char* name, bool required) {
  if (!object.contains(name) || object[name].is_null()) {
    if (required) throw HttpError(400, std::string("office field '") + name + "' is required");
    return {};
  }
  if (!object[name].is_string())
    throw HttpError(400, std::string("office field '") + name + "' must be a string");
  return object[name].get<std::string>();
}

db::PostOffice OfficeFromJson(const json& o) {
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
  return office;
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
  const Pincode pincode = PincodeValue(body["pincode"], "'pincode'");
  std::vector<db::PostOffice> offices;
  if (body.contains("offices")) {
    if (!body["offices"].is_array()) throw HttpError(400, "'offices' must be a list");
    if (body["offices"].size() > 1000) throw HttpError(413, "at most 1000 offices per pincode");
    for (const json& office : body["offices"]) offices.push_back(OfficeFromJson(office));
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
