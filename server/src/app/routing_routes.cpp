// Routing routes: the bin for a pincode under a sort plan, and the plans themselves (read by
// anyone, written by admins as CSV or JSON).

#include <algorithm>

#include "app/db_problems.hpp"
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
  const std::string accept = request.header("Accept").value_or("");
  return accept.find("text/csv") != std::string::npos &&
         accept.find("application/json") == std::string::npos;
}

HttpError BadPlan(std::string detail) {
  return HttpError(400, std::move(detail), "Bad Sort Plan");
}

/// Refuses a field `object` has that `known` does not list: a misspelt field would otherwise be
/// dropped without a word, and the plan saved without what it was meant to say.
void RefuseUnknownFields(const json& object, std::initializer_list<std::string_view> known,
                         const std::string& where) {
  for (const auto& [field, value] : object.items()) {
    if (std::find(known.begin(), known.end(), field) == known.end()) {
      throw BadPlan(where + "unknown field '" + field.substr(0, 40) + "'");
    }
  }
}

db::SortPlan PlanFromJson(const std::string& name, const json& body) {
  if (!body.is_object()) {
    throw BadPlan(R"(expected {"fallback_bin": "…", "rules": [{"prefix": "11", "bin": "…"}]})");
  }
  const auto text = [&](const json& object, const char* field, bool required,
                        const std::string& where = {}) -> std::string {
    if (!object.contains(field)) {
      if (required) throw BadPlan(where + "'" + field + "' is required");
      return {};
    }
    if (!object[field].is_string()) throw BadPlan(where + "'" + field + "' must be a string");
    return object[field].get<std::string>();
  };
  RefuseUnknownFields(body, {"name", "fallback_bin", "description", "rules"}, "");
  db::SortPlan plan;
  plan.name = name;
  if (body.contains("name") && body["name"] != name) {
    throw BadPlan("the body's name differs from the one in the path");
  }
  plan.fallback_bin = text(body, "fallback_bin", true);
  plan.description = text(body, "description", false);
  if (!body.contains("rules") || !body["rules"].is_array()) throw BadPlan("'rules' must be a list");
  for (std::size_t i = 0; i < body["rules"].size(); ++i) {
    const json& rule = body["rules"][i];
    const std::string where = "rules[" + std::to_string(i) + "]: ";
    if (!rule.is_object()) throw BadPlan(where + R"(expected {"prefix": …, "bin": …})");
    RefuseUnknownFields(rule, {"prefix", "bin"}, where);
    plan.rules.push_back({text(rule, "prefix", true, where), text(rule, "bin", true, where)});
  }
  return plan;
}

}  // namespace

HttpResponse GetRoute(const AppContext& context, const HttpRequest& request) {
  const Pincode pincode = PincodeParam(request);
  const std::string plan_name = PlanQuery(request);
  auto connection = context.pool->acquire();
  const db::SortPlan plan = LoadPlan(*connection, plan_name);
  const db::Routing routing = db::RouteWith(plan, pincode);
  auto record = db::LookupPincode(*connection, pincode);
  if (!record && record.error().code != db::ErrorCode::kNotFound) ThrowDbError(record.error());
  json out = {{"pincode", pincode.str()},
              {"plan", plan.name},
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
  if (WantsCsv(request)) {
    return HttpResponse::Bytes("text/csv; charset=utf-8", db::PlanToCsv(plan));
  }
  return HttpResponse::Json(PlanJson(plan).dump());
}

HttpResponse PutSortPlan(const AppContext& context, const HttpRequest& request) {
  const std::string name = PlanNameParam(request);
  db::SortPlan plan;
  const bool csv = request.content_type == "text/csv";
  if (csv) {
    plan = Unwrap(db::ParsePlanCsv(name, request.body), "Bad Sort Plan");
    if (const auto description = request.queryParam("description")) plan.description = *description;
  } else {
    plan = PlanFromJson(name, JsonBody(request));
  }
  if (const auto problem = db::CheckPlan(plan)) ThrowDbError(*problem, "Bad Sort Plan");
  auto connection = context.pool->acquire();
  // The CSV has no place for the description: one fetched as CSV, edited and put back keeps it,
  // unless ?description= says otherwise.
  const db::StoredDescription description = csv && !request.queryParam("description")
                                                ? db::StoredDescription::kKeep
                                                : db::StoredDescription::kReplace;
  const bool replaced = Unwrap(db::SavePlan(*connection, plan, description), "Bad Sort Plan");
  return HttpResponse::Json(PlanJson(LoadPlan(*connection, name)).dump(), replaced ? 200 : 201);
}

}  // namespace pintag::app
