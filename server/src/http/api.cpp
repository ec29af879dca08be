#include "pintag/server/api.hpp"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <nlohmann/json.hpp>

#include "pintag/server/header_text.hpp"
#include "pintag/server/log.hpp"
#include "pintag/server/problem.hpp"
#include "process_metrics.hpp"

namespace pintag::server {
namespace {

constexpr std::size_t kMaxTokenLength = 4096;
// cpp-httplib 0.11.4 bounds each header line (8 KiB) but not how many come: past these, 431.
constexpr std::size_t kMaxHeaderCount = 100;
constexpr std::size_t kMaxHeaderBytes = std::size_t{64} * 1024;

std::optional<std::string> FirstHeader(const HeaderMap& headers, std::string_view name) {
  const auto it = headers.find(name);
  if (it == headers.end()) return std::nullopt;
  return it->second;
}

HttpResponse Unauthorized(std::string detail, bool invalid_token) {
  HttpResponse response = ProblemResponse(401, std::move(detail));
  response.headers.emplace_back("WWW-Authenticate",
                                invalid_token ? R"(Bearer realm="pintag", error="invalid_token")"
                                              : R"(Bearer realm="pintag")");
  return response;
}

/// A query parameter the route does not take, or one given twice, is refused: a misspelt
/// `?pln=hub` printed the default plan's bins unnoticed, and of `?fx=1400&fx=2800` the first was
/// taken without a word. What a route takes is what /openapi.json documents for it.
std::optional<HttpResponse> RefuseQuery(const Route& route, const HttpRequest& request) {
  const auto takes = [&route](const std::string& name) {
    return std::any_of(route.query.begin(), route.query.end(),
                       [&name](const QueryParamDoc& doc) { return doc.name == name; });
  };
  for (auto it = request.query.begin(); it != request.query.end();
       it = request.query.upper_bound(it->first)) {
    const std::string name = it->first.substr(0, 40);
    if (!takes(it->first)) {
      std::string known;
      for (const QueryParamDoc& doc : route.query) known += (known.empty() ? "" : ", ") + doc.name;
      return ProblemResponse(
          400, "unknown query parameter '" + name + "'; " +
                   (known.empty() ? "this route takes none" : "this route takes " + known));
    }
    if (request.query.count(it->first) > 1) {
      return ProblemResponse(400, "the query parameter '" + name + "' is given " +
                                      std::to_string(request.query.count(it->first)) +
                                      " times; give it once");
    }
  }
  return std::nullopt;
}

}  // namespace

Api::Api(Router router, TokenVerifier verifier, HealthCheck health,
         std::shared_ptr<Metrics> metrics, ApiOptions options)
    : router_(std::move(router)),
      verifier_(std::move(verifier)),
      health_(std::move(health)),
      metrics_(metrics ? std::move(metrics) : std::make_shared<Metrics>()),
      options_(std::move(options)) {
  if (options_.web_dir) static_files_.emplace(*options_.web_dir);

  router_.add(MakeRoute(
      "GET", "/livez", Access::kOpen,
      [](const HttpRequest&) { return HttpResponse::Json(R"({"status":"ok"})"); },
      "The process is up", "operations"));
  router_.add(MakeRoute(
      "GET", "/readyz", Access::kOpen,
      [health = health_](const HttpRequest&) {
        const std::optional<std::string> problem = health ? health() : std::nullopt;
        if (problem) return ProblemResponse(Problem{503, "Not Ready", *problem, "about:blank"});
        return HttpResponse::Json(R"({"status":"ready"})");
      },
      "Ready to serve (the database is reachable)", "operations"));
  Route metrics_route = MakeRoute(
      "GET", "/metrics", Access::kOpen,
      [metrics = metrics_](const HttpRequest&) {
        return HttpResponse::Bytes(std::string(Metrics::kContentType),
                                   metrics->renderPrometheus() + ProcessMetricsText());
      },
      "Prometheus metrics (text exposition format)", "operations");
  metrics_route.produces = {"text/plain"};
  router_.add(std::move(metrics_route));
  // The document describes every route including itself, so it is built after this add.
  auto document = std::make_shared<std::string>();
  router_.add(MakeRoute(
      "GET", "/openapi.json", Access::kOpen,
      [document](const HttpRequest&) { return HttpResponse::Json(*document); },
      "This API's OpenAPI 3.1 description", "operations"));
  *document = OpenApiJson(router_, options_.info);
}

Admission Api::admit(std::string_view method, std::string_view path, const HeaderMap& headers,
                     std::string_view request_id) const {
  Admission admission;
  std::size_t header_bytes = 0;
  for (const auto& [name, value] : headers) header_bytes += name.size() + value.size() + 4;
  if (headers.size() > kMaxHeaderCount || header_bytes > kMaxHeaderBytes) {
    admission.rejection =
        ProblemResponse(431, "at most " + std::to_string(kMaxHeaderCount) + " request headers of " +
                                 std::to_string(kMaxHeaderBytes) + " bytes in all are read");
    admission.route_label = "unmatched";
    return admission;
  }
  admission.match = router_.match(method, path);
  const Route* route = admission.match.route;
  // One credential, on every path (open routes and static files too): a proxy that acts on
  // another copy than this server would let a request through as someone else.
  if (const std::size_t copies = headers.count("Authorization"); copies > 1) {
    admission.rejection =
        ProblemResponse(400, "the request carries " + std::to_string(copies) +
                                 " Authorization headers; send one, 'Bearer <token>'");
    admission.route_label = route != nullptr ? route->pattern : "unmatched";
    return admission;
  }
  if (route == nullptr) {
    if (!admission.match.allowed_methods.empty()) {
      std::vector<std::string> allowed = admission.match.allowed_methods;
      if (std::find(allowed.begin(), allowed.end(), "GET") != allowed.end())
        allowed.push_back("HEAD");
      std::string allow;
      for (const std::string& m : allowed) allow += (allow.empty() ? "" : ", ") + m;
      HttpResponse response =
          ProblemResponse(405, std::string(method) + " is not allowed here; use " + allow);
      response.headers.emplace_back("Allow", allow);
      admission.rejection = std::move(response);
      // The path is one of ours: an operator wants to see which route is called wrongly.
      admission.route_label = admission.match.allowed_pattern;
      return admission;
    }
    if (static_files_ && (method == "GET" || method == "HEAD") &&
        std::string_view(path).rfind("/api/", 0) != 0) {
      admission.is_static = true;
      admission.route_label = "static";
      return admission;
    }
    admission.rejection = ProblemResponse(
        404, "no route for " + std::string(method) + " " + std::string(path.substr(0, 200)));
    admission.route_label = "unmatched";
    return admission;
  }
  admission.route_label = route->pattern;
  if (route->answers_before_body) {
    HttpRequest bare;
    bare.method = std::string(method);
    bare.path = std::string(path);
    bare.path_params = admission.match.params;
    admission.rejection = InvokeHandler(route->handler, bare);
    return admission;
  }

  // Bearer auth, before a byte of the body is read.
  if (route->access != Access::kOpen) {
    const std::optional<std::string> authorization = FirstHeader(headers, "Authorization");
    if (!authorization) {
      admission.rejection =
          Unauthorized("this route needs a bearer token (Authorization: Bearer …)", false);
      return admission;
    }
    const std::string_view value = Trim(*authorization);
    const std::size_t space = value.find(' ');
    if (space == std::string_view::npos || Lower(value.substr(0, space)) != "bearer") {
      admission.rejection =
          Unauthorized("the Authorization header must be 'Bearer <token>'", false);
      return admission;
    }
    const std::string_view token = Trim(value.substr(space + 1));
    std::optional<Principal> principal;
    try {
      if (!token.empty() && token.size() <= kMaxTokenLength && verifier_)
        principal = verifier_(token);
    } catch (const HttpError& e) {
      if (e.problem().status >= 500) {
        LogRequestError(request_id, std::string(method) + " " + std::string(path) + ": " +
                                        std::to_string(e.problem().status) + " " +
                                        e.problem().detail + " (checking the bearer token)");
      }
      admission.rejection = ProblemResponse(e.problem());
      return admission;
    }
    if (!principal) {
      admission.rejection = Unauthorized("the bearer token is not valid", true);
      return admission;
    }
    if (!Allows(route->access, principal->role)) {
      admission.rejection =
          ProblemResponse(403, "a " + std::string(ToString(principal->role)) +
                                   " token may not call this route; it needs " +
                                   std::string(ToString(route->access)) +
                                   (route->access == Access::kAdmin ? "" : " or admin"));
      // Kept for the access line, which names the token refused (no handler runs).
      admission.principal = std::move(principal);
      return admission;
    }
    admission.principal = std::move(principal);
  }

  // The declared body: its length against the limit, its media type against the route's.
  std::size_t declared_bytes = 0;
  if (const auto length = FirstHeader(headers, "Content-Length")) {
    const std::string_view text = Trim(*length);
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), declared_bytes);
    if (ec == std::errc::result_out_of_range ||
        (ec == std::errc() && declared_bytes > options_.max_body_bytes)) {
      admission.rejection = BodyTooLargeResponse(options_.max_body_bytes);
      return admission;
    }
    if (ec != std::errc() || end != text.data() + text.size()) {
      admission.rejection = ProblemResponse(400, "malformed Content-Length");
      return admission;
    }
  }
  // "Content-Length: 00" is no body either.
  const bool has_body = FirstHeader(headers, "Transfer-Encoding").has_value() || declared_bytes > 0;
  if (route->consumes.empty() && has_body) {
    // Dropped unread before: a body sent to retire a pincode or revoke a token ({"reason": …},
    // a form) was answered 200 as if read, where every other route refuses what it cannot use.
    admission.rejection = ProblemResponse(
        400, route->method + " " + route->pattern + " takes no body; send the request without one");
    return admission;
  }
  if (!route->consumes.empty() && has_body) {
    const std::string type = MediaType(FirstHeader(headers, "Content-Type").value_or(""));
    if (std::find(route->consumes.begin(), route->consumes.end(), type) == route->consumes.end()) {
      std::string accepted;
      for (const std::string& t : route->consumes) accepted += (accepted.empty() ? "" : ", ") + t;
      admission.rejection = ProblemResponse(
          415, "this route takes " + accepted + ", not '" + type.substr(0, 100) + "'");
      return admission;
    }
  }
  return admission;
}

HttpResponse Api::invoke(const Admission& admission, HttpRequest request) const {
  if (admission.rejection) return *admission.rejection;
  if (admission.is_static) return static_files_->serve(request.path);
  if (std::optional<HttpResponse> refused = RefuseQuery(*admission.match.route, request)) {
    return *refused;
  }
  request.path_params = admission.match.params;
  request.principal = admission.principal;
  if (request.content_type.empty()) {
    request.content_type = MediaType(request.header("Content-Type").value_or(""));
  }
  return InvokeHandler(admission.match.route->handler, request);
}

HttpResponse Api::handle(HttpRequest request) const {
  const auto start = std::chrono::steady_clock::now();
  const std::string method = request.method;
  const Admission admission =
      admit(request.method, request.path, request.headers, request.request_id);
  HttpResponse response;
  if (!admission.rejection && request.body.size() > options_.max_body_bytes) {
    response = BodyTooLargeResponse(options_.max_body_bytes);
  } else {
    response = invoke(admission, std::move(request));
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  metrics_->observeRequest(admission.route_label, method, response.status, seconds);
  return response;
}

}  // namespace pintag::server
