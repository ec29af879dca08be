#pragma once
// The application's /api/v1 routes beyond the label routes, one file per group. Each adds its
// routes to the table with their access rule and OpenAPI notes.

#include <memory>
#include <nlohmann/json.hpp>

#include "app/context.hpp"
#include "pintag/server/label_routes.hpp"
#include "pintag/server/router.hpp"

namespace pintag::app {

// The route files speak the HTTP layer's vocabulary throughout.
using nlohmann::json;
using server::Access;
using server::HttpError;
using server::HttpRequest;
using server::HttpResponse;
using server::MakeRoute;
using server::Route;

/// A route group's handler: a plain function of the shared context and the request.
using ContextHandler = HttpResponse (*)(const AppContext&, const HttpRequest&);

/// `f` as a route handler over `context` (kept alive by the handler).
inline server::Handler Bind(const std::shared_ptr<const AppContext>& context, ContextHandler f) {
  return [context, f](const HttpRequest& request) { return f(*context, request); };
}

/// GET /pincodes/{pin}, GET /pincodes, GET /keys/{key}, POST /pincodes, POST
/// /pincodes/{pin}/retire.
void AddRegistryRoutes(server::Router& router, const std::shared_ptr<const AppContext>& context);
/// GET /route/{pin}, GET /sortplans, GET and PUT /sortplans/{name}.
void AddRoutingRoutes(server::Router& router, const std::shared_ptr<const AppContext>& context);
/// POST /tokens, GET /tokens, DELETE /tokens/{id}, POST /tokens/{id}/revoke.
void AddTokenRoutes(server::Router& router, const std::shared_ptr<const AppContext>& context);
/// POST /detect.
void AddDetectRoutes(server::Router& router, std::shared_ptr<const AppContext> context);

/// The registry as the label routes see it: unknown pincode 404, retired 410, unknown plan 404.
server::LabelContentProvider RegistryLabelProvider(
    const std::shared_ptr<const AppContext>& context);

}  // namespace pintag::app
