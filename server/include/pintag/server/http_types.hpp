#pragma once
// The HTTP layer's plain values: a request in, a response out. Handlers are functions between
// them, so they are tested without sockets; only http_server.cpp knows cpp-httplib.

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace pintag::server {

/// What a route requires, and what a verified token grants. Admin satisfies every requirement;
/// replica only pulls registry snapshots (docs/SCALING.md).
/// The tokens and their stored role names are db's (`db::Role`); the application maps a verified
/// token's role onto this, so this layer needs no database.
enum class Access { kOpen, kCounter, kScanner, kAdmin, kReplica };

std::string_view ToString(Access access);  ///< "open", "counter", "scanner", "admin", "replica"
/// Whether a token granting `granted` may call a route requiring `required`.
bool Allows(Access required, Access granted);

/// Who is calling, once a bearer token was verified.
struct Principal {
  std::string id;                  ///< token id or name, for logs; never the secret
  Access role = Access::kCounter;  ///< what the token was issued for: counter, scanner or admin
};

/// Header names compare case-insensitively (RFC 9110).
struct CaseInsensitiveLess {
  bool operator()(std::string_view a, std::string_view b) const;
  using is_transparent = void;
};
using HeaderMap = std::multimap<std::string, std::string, CaseInsensitiveLess>;

/// One part of a multipart/form-data body (e.g. the `image` field of POST /detect).
struct FormPart {
  std::string name;
  std::string filename;
  std::string content_type;
  std::string content;
};

struct HttpRequest {
  std::string method;                              ///< "GET", "POST", … (HEAD is routed as GET)
  std::string path;                                ///< decoded path, no query
  std::map<std::string, std::string> path_params;  ///< from the route pattern, e.g. {"pin", …}
  std::multimap<std::string, std::string> query;   ///< decoded query parameters
  HeaderMap headers;
  std::string body;                    ///< the raw body, unless it was multipart/form-data
  std::vector<FormPart> parts;         ///< the parts of a multipart/form-data body
  std::string content_type;            ///< media type of the body without parameters, lower case
  std::optional<Principal> principal;  ///< set when the route needs a role and the token passed
  std::string request_id;  ///< X-Request-Id: the client's when sane, else made up (log.hpp)

  /// The path parameter `name`; empty when absent.
  std::string pathParam(std::string_view name) const;
  /// The first query parameter `name`, if given.
  std::optional<std::string> queryParam(std::string_view name) const;
  /// The first form part called `name`, if any.
  const FormPart* part(std::string_view name) const;
  /// The first header `name`, if given.
  std::optional<std::string> header(std::string_view name) const;
};

struct HttpResponse {
  int status = 200;
  std::string content_type = "application/json";
  std::string body;
  std::vector<std::pair<std::string, std::string>> headers;  ///< extra headers

  static HttpResponse Json(std::string body, int status = 200);
  static HttpResponse Bytes(std::string content_type, std::string body, int status = 200);
  static HttpResponse Bytes(std::string content_type, const std::vector<std::uint8_t>& body);
  static HttpResponse Text(std::string body, int status = 200);
};

using Handler = std::function<HttpResponse(const HttpRequest&)>;

/// Checks a bearer token; the registry supplies it (tokens table). Nothing for an unknown,
/// revoked or malformed token; throws HttpError (answered as it says) when the token cannot be
/// checked, e.g. 503 with the database unreachable. Must be thread-safe: it runs on the worker
/// threads.
using TokenVerifier = std::function<std::optional<Principal>(std::string_view token)>;

}  // namespace pintag::server
