#pragma once
// The application's route handlers, one file per group. Each is a plain function of the shared
// context and the request; route_table.cpp gives each its method, path and role.

#include <nlohmann/json.hpp>

#include "app/context.hpp"
#include "pintag/server/http_types.hpp"
#include "pintag/server/problem.hpp"

namespace pintag::app {

// The handler files speak the HTTP layer's vocabulary throughout.
using nlohmann::json;
using server::HttpError;
using server::HttpRequest;
using server::HttpResponse;

using RouteHandler = HttpResponse (*)(const AppContext&, const HttpRequest&);

// registry_routes.cpp: pincodes and keys.
HttpResponse GetPincode(const AppContext& context, const HttpRequest& request);
HttpResponse SearchPincodes(const AppContext& context, const HttpRequest& request);
HttpResponse GetKey(const AppContext& context, const HttpRequest& request);
HttpResponse PostPincode(const AppContext& context, const HttpRequest& request);
HttpResponse PostRetirePincode(const AppContext& context, const HttpRequest& request);

// label_routes.cpp: tags and printable labels.
/// A tag PNG's black square side when `px` is not given: 256, or --max-tag-px when smaller.
int DefaultTagPx(const AppContext& context);
HttpResponse GetTagPng(const AppContext& context, const HttpRequest& request);
HttpResponse GetTagSvg(const AppContext& context, const HttpRequest& request);
HttpResponse GetLabelPdf(const AppContext& context, const HttpRequest& request);
HttpResponse GetLabelPng(const AppContext& context, const HttpRequest& request);
HttpResponse GetLabelSvg(const AppContext& context, const HttpRequest& request);
HttpResponse PostLabels(const AppContext& context, const HttpRequest& request);

// detect_route.cpp: tags in a photo.
HttpResponse PostDetect(const AppContext& context, const HttpRequest& request);

// routing_routes.cpp: bins and sort plans.
HttpResponse GetRoute(const AppContext& context, const HttpRequest& request);
HttpResponse GetSortPlans(const AppContext& context, const HttpRequest& request);
HttpResponse GetSortPlan(const AppContext& context, const HttpRequest& request);
HttpResponse PutSortPlan(const AppContext& context, const HttpRequest& request);
HttpResponse DeleteSortPlan(const AppContext& context, const HttpRequest& request);

// replication_routes.cpp: the registry version served, and the primary's snapshot.
HttpResponse GetRegistryStatus(const AppContext& context, const HttpRequest& request);
HttpResponse GetRegistrySnapshot(const AppContext& context, const HttpRequest& request);

// token_routes.cpp: bearer tokens.
HttpResponse PostToken(const AppContext& context, const HttpRequest& request);
HttpResponse GetTokens(const AppContext& context, const HttpRequest& request);
HttpResponse RevokeToken(const AppContext& context, const HttpRequest& request);

}  // namespace pintag::app
