#pragma once
// The route table: method, path pattern, who may call, handler, and what OpenAPI says about it.
// Patterns are literal segments and parameters, a parameter optionally with a literal suffix in
// its segment: "/api/v1/pincodes/{pin}", "/api/v1/tags/{pin}.png".

#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "pintag/server/http_types.hpp"

namespace pintag::server {

/// A query parameter, for the OpenAPI description.
struct QueryParamDoc {
  std::string name;
  std::string description;
  std::string type = "string";  ///< JSON schema type: "string", "integer", "number", "boolean"
  bool required = false;
};

/// A header a route reads or answers with, as OpenAPI describes it.
struct HeaderDoc {
  std::string name;
  std::string description;
};

struct Route {
  std::string method;   ///< "GET", "POST", "PUT", "DELETE", "PATCH"
  std::string pattern;  ///< see the header comment
  Access access = Access::kOpen;
  Handler handler;
  std::string summary;                ///< one line for OpenAPI
  std::vector<std::string> produces;  ///< success media types; empty = application/json
  std::vector<int> success = {200};   ///< the statuses a success answers with (201 Created, …)
  std::vector<QueryParamDoc> query;   ///< documented query parameters
  std::vector<HeaderDoc> request_headers;   ///< documented headers it reads (If-Match, …)
  std::vector<HeaderDoc> response_headers;  ///< documented headers of its successes (ETag, …)
  std::vector<std::string> consumes;        ///< request body media types; empty = no body
  std::string tag = "api";                  ///< OpenAPI tag grouping the route
  bool hidden = false;                      ///< left out of OpenAPI (static files)
  /// The handler answers from the method and path alone, at admission: before a token is asked
  /// for or a byte of the body is read (a replica's refusal of a write, whatever it carries).
  bool answers_before_body = false;
  /// Statuses whose answers are routine, asked for over and over with nothing new (a replica's
  /// poll answered 304): their access lines are written at most once a minute for each client
  /// and token (RoutineAccessThrottle).
  std::vector<int> routine_statuses;
};

/// A route with the fields every route sets; set produces, query and consumes on the result.
Route MakeRoute(std::string method, std::string pattern, Access access, Handler handler,
                std::string summary, std::string tag = "api");

struct RouteMatch {
  const Route* route = nullptr;               ///< null when nothing matched
  std::map<std::string, std::string> params;  ///< path parameters of the matched route
  std::vector<std::string> allowed_methods;   ///< when the path matched other methods only
  std::string allowed_pattern;  ///< then, the pattern the path matched (a 405's metrics label)
};

class Router {
 public:
  /// Adds a route; throws std::invalid_argument for a malformed pattern or a duplicate.
  Router& add(Route route);

  /// The route for `method` (HEAD matches GET) and `path`. When the path exists for other methods
  /// only, `route` is null, `allowed_methods` lists them (for 405 and Allow) and
  /// `allowed_pattern` is the pattern it matched; where a literal pattern and a parameter
  /// pattern both match, the literal one (as for a match), while `allowed_methods` lists the
  /// methods of both, each once.
  RouteMatch match(std::string_view method, std::string_view path) const;

  const std::vector<Route>& routes() const { return routes_; }

 private:
  struct Segment {
    bool param = false;
    std::string text;    ///< literal, or the parameter's name
    std::string suffix;  ///< literal after the parameter within the segment
  };
  struct Compiled {
    std::vector<Segment> segments;
  };
  static Compiled Compile(const std::string& pattern);
  static bool Matches(const Compiled& compiled, const std::vector<std::string_view>& parts,
                      std::map<std::string, std::string>* params);

  std::vector<Route> routes_;
  std::vector<Compiled> compiled_;
};

}  // namespace pintag::server
