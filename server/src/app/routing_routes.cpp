// Routing routes: the bin for a pincode under a sort plan, and the plans themselves (read by
// anyone, written by admins as CSV or JSON).

#include <algorithm>
#include <map>
#include <optional>
#include <string>

#include "app/accept_header.hpp"
#include "app/db_problems.hpp"
#include "app/entity_tags.hpp"
#include "app/params.hpp"
#include "app/routes.hpp"

namespace pintag::app {
namespace {

json PlanJson(const db::SortPlan& plan) {
  json rules = json::array();
  for (const db::SortRule& rule : plan.rules)
    rules.push_back({{"prefix", rule.prefix}, {"bin", rule.bin}});
  return {{"name", plan.name},
          {"fallback_bin", plan.fallback_bin},
          {"description", plan.description},
          {"rules", std::move(rules)}};
}

bool WantsCsv(const HttpRequest& request) {
  if (const auto format = request.queryParam("format")) {
    if (*format == "csv") return true;
    if (*format == "json") return false;
    throw HttpError(400, "format must be csv or json");
  }
  // By the weights, as RFC 9110 reads the header: a substring test answered CSV to
  // "text/csv;q=0" and JSON to "application/json;q=0.1, text/csv". JSON unless CSV weighs more.
  const std::optional<std::string> accept = request.header("Accept");
  if (!accept) return false;
  return AcceptQuality(*accept, "text/csv") > AcceptQuality(*accept, "application/json");
}

HttpError BadPlan(std::string detail) {
  return HttpError(400, std::move(detail), "Bad Sort Plan");
}

/// A plan's fault as a problem: 400 "Bad Sort Plan" for what is wrong in it; the others (413 over
/// the rule limit, 412, 503, …) keep their status's own title.
[[noreturn]] void ThrowPlanError(const db::Error& error) {
  ThrowDbError(error, error.code == db::ErrorCode::kInvalid    ? "Bad Sort Plan"
                      : error.code == db::ErrorCode::kConflict ? "Sort Plan Reads Alike"
                                                               : "");
}

/// Refuses a field `object` has that `known` does not list (UnknownField), as a bad plan.
void RefuseUnknownFields(const json& object, std::initializer_list<std::string_view> known,
                         const std::string& where) {
  if (const std::optional<std::string> field = UnknownField(object, known)) {
    throw BadPlan(where + "unknown field '" + field->substr(0, 40) + "'");
  }
}

db::SortPlan PlanFromJson(const std::string& name, const json& body) {
  if (!body.is_object()) {
    throw BadPlan(R"(expected {"fallback_bin": "…", "rules": [{"prefix": "11", "bin": "…"}]})");
  }
  const auto text = [&](const json& object, const char* field, bool required,
                        const std::string& where = {}) -> std::string {
    if (!object.contains(field) || object[field].is_null()) {  // null is leaving it out
      if (required) throw BadPlan(where + "'" + field + "' is required");
      return {};
    }
    if (!object[field].is_string()) throw BadPlan(where + "'" + field + "' must be a string");
    return object[field].get<std::string>();
  };
  RefuseUnknownFields(body, {"name", "fallback_bin", "description", "rules"}, "");
  db::SortPlan plan;
  plan.name = name;
  if (body.contains("name") && !body["name"].is_null() && body["name"] != name) {
    throw BadPlan("the body's name differs from the one in the path");
  }
  plan.fallback_bin = text(body, "fallback_bin", true);
  plan.description = text(body, "description", false);
  if (!body.contains("rules") || !body["rules"].is_array()) throw BadPlan("'rules' must be a list");
  if (body["rules"].size() > db::kMaxPlanRules) {
    throw HttpError(413, "the plan has " + std::to_string(body["rules"].size()) +
                             " rules; a sort plan has at most " +
                             std::to_string(db::kMaxPlanRules));
  }
  std::map<std::string, std::size_t> index_of;  // each rule's prefix, and where it was
  for (std::size_t i = 0; i < body["rules"].size(); ++i) {
    const json& rule = body["rules"][i];
    const std::string where = "rules[" + std::to_string(i) + "]: ";
    if (!rule.is_object()) throw BadPlan(where + R"(expected {"prefix": …, "bin": …})");
    RefuseUnknownFields(rule, {"prefix", "bin"}, where);
    db::SortRule read{text(rule, "prefix", true, where), text(rule, "bin", true, where)};
    if (const auto problem = db::CheckRule(read)) throw BadPlan(where + problem->message);
    const auto [first, inserted] = index_of.try_emplace(read.prefix, i);
    if (!inserted) {
      throw BadPlan(where + "prefix " + read.prefix + " appears twice (first at rules[" +
                    std::to_string(first->second) + "])");
    }
    plan.rules.push_back(std::move(read));
  }
  return plan;
}

// A plan's ETag: its version (db::PlanVersion), quoted; the CSV form adds "-csv", since a strong
// ETag names one representation and the JSON and CSV of one version differ.
constexpr std::string_view kCsvTagSuffix = "-csv";

std::string PlanETag(const std::string& version, bool csv) {
  return "\"" + version + (csv ? std::string(kCsvTagSuffix) : std::string()) + "\"";
}

/// The plan versions a header's tags name, either form. `strong`: If-Match compares strongly,
/// so a weak tag matches nothing there; If-None-Match compares weakly.
db::PlanVersions VersionsOf(const EntityTagList& list, bool strong) {
  db::PlanVersions versions{list.any, {}};
  for (const EntityTag& tag : list.tags) {
    if (strong && tag.weak) continue;
    std::string_view version = tag.opaque;
    if (version.ends_with(kCsvTagSuffix)) version.remove_suffix(kCsvTagSuffix.size());
    versions.versions.emplace_back(version);
  }
  return versions;
}

/// If-Match and If-None-Match of a PUT as the condition the stored plan must meet.
db::PlanCondition PlanConditionOf(const HttpRequest& request) {
  db::PlanCondition condition;
  if (const auto match = EntityTagsHeader(request, "If-Match")) {
    condition.match = VersionsOf(*match, true);
  }
  if (const auto none_match = EntityTagsHeader(request, "If-None-Match")) {
    condition.none_match = VersionsOf(*none_match, false);
  }
  return condition;
}

HttpResponse PlanResponse(std::string body, std::string content_type, const std::string& version,
                          bool csv, int status = 200) {
  HttpResponse response = HttpResponse::Bytes(std::move(content_type), std::move(body), status);
  response.headers.emplace_back("ETag", PlanETag(version, csv));
  // JSON or CSV is chosen by Accept as well as ?format=.
  response.headers.emplace_back("Vary", "Accept");
  return response;
}

}  // namespace

HttpResponse GetRoute(const AppContext& context, const HttpRequest& request) {
  const Pincode pincode = PincodeParam(request);
  const std::string plan_name = PlanQuery(request);
  auto connection = context.pool->acquire();
  // The six prefixes of the pincode looked up by index, not the whole plan read (a plan may
  // hold up to db::kMaxPlanRules rules).
  auto routed = db::Route(*connection, pincode, plan_name);
  if (!routed && routed.error().code == db::ErrorCode::kNotFound) ThrowUnknownPlan(routed.error());
  const db::Routing routing = Unwrap(std::move(routed));
  auto record = db::LookupPincode(*connection, pincode);
  if (!record && record.error().code != db::ErrorCode::kNotFound) ThrowDbError(record.error());
  json out = {{"pincode", pincode.str()},
              {"plan", plan_name},
              {"bin", routing.bin},
              {"matched_prefix", routing.rule ? json(routing.rule->prefix) : json(nullptr)},
              {"fallback", !routing.rule.has_value()},
              {"status", record ? db::ToString(record->status) : "unknown"},
              {"key", record ? json(record->key.value()) : json(nullptr)}};
  return HttpResponse::Json(out.dump());
}

HttpResponse GetSortPlans(const AppContext& context, const HttpRequest&) {
  auto connection = context.pool->acquire();
  json plans = json::array();
  for (const std::string& name : Unwrap(db::ListPlans(*connection))) {
    const db::SortPlan plan = LoadPlan(*connection, name);
    plans.push_back({{"name", plan.name},
                     {"fallback_bin", plan.fallback_bin},
                     {"description", plan.description},
                     {"rules", plan.rules.size()}});
  }
  return HttpResponse::Json(json{{"plans", std::move(plans)}}.dump());
}

HttpResponse GetSortPlan(const AppContext& context, const HttpRequest& request) {
  auto connection = context.pool->acquire();
  const db::SortPlan plan = LoadPlan(*connection, PlanNameParam(request));
  const std::string version = db::PlanVersion(plan);
  const bool csv = WantsCsv(request);
  // A client that holds this version (a script keeping plans in step) is told so, without the
  // plan again. A malformed If-None-Match on a GET is ignored (RFC 9110 lets a server), as it was
  // before the route read it: the whole plan is sent.
  std::optional<EntityTagList> none_match;
  try {
    none_match = EntityTagsHeader(request, "If-None-Match");
  } catch (const HttpError&) {
    none_match.reset();
  }
  if (none_match && NoneMatchNames(*none_match, PlanETag(version, csv))) {
    // cpp-httplib sends it with "Content-Length: 0", where RFC 9110 (8.6) wants none or the 200's
    // length. The 200's was tried: cpp-httplib's own client (0.11.4) then waits for that many bytes
    // of body after a 304, and so would other clients that do not know a 304 has none.
    return PlanResponse("", csv ? "text/csv; charset=utf-8" : "application/json", version, csv,
                        304);
  }
  if (csv) {
    return PlanResponse(db::PlanToCsv(plan), "text/csv; charset=utf-8", version, true);
  }
  return PlanResponse(PlanJson(plan).dump(), "application/json", version, false);
}

HttpResponse PutSortPlan(const AppContext& context, const HttpRequest& request) {
  const std::string name = PlanNameParam(request);
  db::SortPlan plan;
  const bool csv = request.content_type == "text/csv";
  if (csv) {
    auto parsed = db::ParsePlanCsv(name, request.body);
    if (!parsed) ThrowPlanError(parsed.error());
    plan = std::move(parsed).value();
    if (const auto description = request.queryParam("description")) plan.description = *description;
  } else {
    // Dropped without a word before: a JSON plan's description is the body's own.
    if (request.queryParam("description")) {
      throw HttpError(400,
                      "?description= is for CSV bodies; a JSON plan gives \"description\" in "
                      "its body",
                      "Bad Sort Plan");
    }
    plan = PlanFromJson(name, JsonBody(request));
  }
  if (const auto problem = db::CheckPlan(plan)) ThrowPlanError(*problem);
  auto connection = context.pool->acquire();
  // The CSV has no place for the description: one fetched as CSV, edited and put back keeps it,
  // unless ?description= says otherwise.
  const db::StoredDescription description = csv && !request.queryParam("description")
                                                ? db::StoredDescription::kKeep
                                                : db::StoredDescription::kReplace;
  // Without If-Match or If-None-Match the plan is overwritten whatever it was (docs/API.md).
  auto saved = db::SavePlanIf(*connection, plan, PlanConditionOf(request), description);
  if (!saved) ThrowPlanError(saved.error());
  return PlanResponse(PlanJson(saved->plan).dump(), "application/json", saved->version, false,
                      saved->replaced ? 200 : 201);
}

HttpResponse DeleteSortPlan(const AppContext& context, const HttpRequest& request) {
  const std::string name = PlanNameParam(request);
  auto connection = context.pool->acquire();
  // Without If-Match the plan is deleted whatever it was, as a PUT without it overwrites.
  auto deleted = db::DeletePlan(*connection, name, PlanConditionOf(request));
  if (!deleted && deleted.error().code == db::ErrorCode::kConflict) {
    throw HttpError(409, deleted.error().message, "Default Sort Plan");
  }
  // The title every other route gives an unknown plan.
  if (!deleted && deleted.error().code == db::ErrorCode::kNotFound)
    ThrowUnknownPlan(deleted.error());
  if (!deleted) ThrowPlanError(deleted.error());
  // The plan as it was, so that a mistaken delete can be put back with PUT.
  return PlanResponse(PlanJson(*deleted).dump(), "application/json", db::PlanVersion(*deleted),
                      false);
}

}  // namespace pintag::app
