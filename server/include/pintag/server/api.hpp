#pragma once
// The application as the HTTP layer sees it: the route table plus auth, limits, the problem+json
// wrapper, metrics, the operational routes (/livez, /readyz, /metrics, /openapi.json) and static
// files. Everything here works on plain values, so it is tested without sockets; HttpServer only
// adapts cpp-httplib to it.

#include <cstddef>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "pintag/server/http_types.hpp"
#include "pintag/server/metrics.hpp"
#include "pintag/server/openapi.hpp"
#include "pintag/server/router.hpp"
#include "pintag/server/static_files.hpp"

namespace pintag::server {

/// Readiness: nothing when ready, else why not (e.g. "database unreachable: …"). Thread-safe.
using HealthCheck = std::function<std::optional<std::string>()>;

inline constexpr std::size_t kDefaultMaxBodyBytes = std::size_t{25} * 1024 * 1024;
/// Parts of a multipart/form-data body; more answer 413. A photo upload needs one.
inline constexpr std::size_t kMaxFormParts = 16;

struct ApiOptions {
  std::size_t max_body_bytes = kDefaultMaxBodyBytes;  ///< larger bodies answer 413
  std::optional<std::filesystem::path> web_dir;       ///< static files; none = no static files
  ApiInfo info;                                       ///< OpenAPI title and version
};

/// The first stage of a request, from its method, path and headers only (before the body is
/// read): the route, the verified principal, and the rejection to send instead, if any.
struct Admission {
  RouteMatch match;
  /// The token's, once verified: also on a rejection that comes after (a 403 for its role, 411,
  /// 413, 415), for the access line; no handler runs for a rejected request.
  std::optional<Principal> principal;
  std::optional<HttpResponse> rejection;  ///< 404, 405, 401, 403, 411, 413, 415 as problem+json
  std::string route_label;                ///< metrics label: the pattern, "static", "unmatched"
  bool is_static = false;                 ///< a GET outside the table, served from web_dir
};

class Api {
 public:
  /// Adds the operational routes to `router`, then freezes it. `verifier` may be empty (every
  /// route needing a role then answers 401); `health` may be empty (always ready).
  Api(Router router, TokenVerifier verifier, HealthCheck health, std::shared_ptr<Metrics> metrics,
      ApiOptions options = {});

  /// Stage one: route, method, bearer auth, declared body length and content type. A 5xx refusal
  /// (the token store failing) is logged under `request_id`, as a handler's is.
  Admission admit(std::string_view method, std::string_view path, const HeaderMap& headers,
                  std::string_view request_id = {}) const;

  /// Stage two: runs the admitted route's handler (or serves the static file) through the
  /// problem+json wrapper. `request` carries the body; its path_params and principal are filled
  /// from `admission`.
  HttpResponse invoke(const Admission& admission, HttpRequest request) const;

  /// Both stages plus the body limit and metrics, for callers without a socket (tests).
  HttpResponse handle(HttpRequest request) const;

  Metrics& metrics() const { return *metrics_; }
  const Router& router() const { return router_; }
  const ApiOptions& options() const { return options_; }

 private:
  Router router_;
  TokenVerifier verifier_;
  HealthCheck health_;
  std::shared_ptr<Metrics> metrics_;
  ApiOptions options_;
  std::optional<StaticFiles> static_files_;
};

}  // namespace pintag::server
