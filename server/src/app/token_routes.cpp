// Token routes (admin only): create (the secret is in this one answer), list, revoke.

#include <charconv>

#include "app/common.hpp"
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

HttpResponse CreateTokenRoute(const AppContext& context, const HttpRequest& request) {
  const json body = JsonBody(request);
  if (!body.is_object() || !body.contains("role") || !body["role"].is_string()) {
    throw HttpError(400, R"(expected {"role": "admin|counter|scanner|replica", "label": "…"})");
  }
  const auto role = db::ParseRole(body["role"].get<std::string>());
  if (!role) throw HttpError(400, "role must be admin, counter, scanner or replica");
  std::string label;
  if (body.contains("label")) {
    if (!body["label"].is_string()) throw HttpError(400, "'label' must be a string");
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

HttpResponse ListTokensRoute(const AppContext& context, const HttpRequest&) {
  auto connection = context.pool->acquire();
  json tokens = json::array();
  for (const db::TokenInfo& token : Unwrap(db::ListTokens(*connection)))
    tokens.push_back(TokenJson(token));
  return HttpResponse::Json(json{{"tokens", std::move(tokens)}}.dump());
}

HttpResponse RevokeTokenRoute(const AppContext& context, const HttpRequest& request) {
  const std::string text = request.pathParam("id");
  std::int64_t id = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), id);
  if (ec != std::errc() || end != text.data() + text.size() || id <= 0) {
    throw HttpError(400, "a token id is a positive integer, got '" + text.substr(0, 40) + "'");
  }
  auto connection = context.pool->acquire();
  return HttpResponse::Json(
      TokenJson(Unwrap(db::RevokeToken(*connection, id), "Unknown Token")).dump());
}

}  // namespace

void AddTokenRoutes(server::Router& router, const std::shared_ptr<const AppContext>& context) {
  Route create =
      MakeRoute("POST", "/api/v1/tokens", Access::kAdmin, Bind(context, CreateTokenRoute),
                R"(Create a token {"role", "label"}; the answer holds its secret, once)", "tokens");
  create.consumes = {"application/json"};
  router.add(std::move(create));
  router.add(MakeRoute("GET", "/api/v1/tokens", Access::kAdmin, Bind(context, ListTokensRoute),
                       "Every token (never a secret), revoked ones included", "tokens"));
  router.add(MakeRoute("DELETE", "/api/v1/tokens/{id}", Access::kAdmin,
                       Bind(context, RevokeTokenRoute), "Revoke a token (permanent)", "tokens"));
  router.add(MakeRoute("POST", "/api/v1/tokens/{id}/revoke", Access::kAdmin,
                       Bind(context, RevokeTokenRoute), "Revoke a token (same as DELETE)",
                       "tokens"));
}

}  // namespace pintag::app
