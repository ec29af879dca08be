// Token routes (admin only): create (the secret is in this one answer), list, revoke.

#include "app/db_problems.hpp"
#include "app/params.hpp"
#include "app/routes.hpp"
#include "pintag/db/tokens.hpp"

namespace pintag::app {
namespace {

json TokenJson(const db::TokenInfo& token) {
  return {{"id", token.id},
          {"role", db::ToString(token.role)},
          {"label", token.label},
          {"created_at", token.created_at},
          {"revoked_at", token.revoked_at ? json(*token.revoked_at) : json(nullptr)}};
}

}  // namespace

HttpResponse PostToken(const AppContext& context, const HttpRequest& request) {
  const json body = JsonBody(request);
  if (!body.is_object() || !body.contains("role") || !body["role"].is_string()) {
    throw HttpError(400, R"(expected {"role": "admin|counter|scanner|replica", "label": "…"})");
  }
  // Refused, not dropped: a misspelt "lable" would otherwise issue a token with no label.
  if (const std::optional<std::string> field = UnknownField(body, {"role", "label"})) {
    throw HttpError(
        400, "unknown field '" + field->substr(0, 40) + "': a token has 'role' and 'label' only");
  }
  const auto role = db::ParseRole(body["role"].get<std::string>());
  if (!role) throw HttpError(400, "role must be admin, counter, scanner or replica");
  std::string label;
  if (body.contains("label") && !body["label"].is_null()) {  // null: no label, as left out
    if (!body["label"].is_string()) throw HttpError(400, "'label' must be a string or null");
    label = body["label"].get<std::string>();
  }
  auto connection = context.pool->acquire();
  const db::NewToken token = Unwrap(db::CreateToken(*connection, *role, label));
  json out = TokenJson(token.info);
  out["secret"] = token.secret;
  HttpResponse response = HttpResponse::Json(out.dump(), 201);
  response.headers.emplace_back("Cache-Control", "no-store");
  return response;
}

HttpResponse GetTokens(const AppContext& context, const HttpRequest&) {
  auto connection = context.pool->acquire();
  json tokens = json::array();
  for (const db::TokenInfo& token : Unwrap(db::ListTokens(*connection)))
    tokens.push_back(TokenJson(token));
  return HttpResponse::Json(json{{"tokens", std::move(tokens)}}.dump());
}

HttpResponse RevokeToken(const AppContext& context, const HttpRequest& request) {
  const std::int64_t id = TokenIdParam(request);
  auto connection = context.pool->acquire();
  auto revoked = db::RevokeToken(*connection, id, db::LastAdmin::kKeep);
  if (!revoked && revoked.error().code == db::ErrorCode::kConflict) {
    throw HttpError(409, revoked.error().message, "Last Admin Token");
  }
  return HttpResponse::Json(TokenJson(Unwrap(std::move(revoked), "Unknown Token")).dump());
}

}  // namespace pintag::app
