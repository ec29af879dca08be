#include "replica/replica_routes.hpp"

#include "pintag/server/problem.hpp"

namespace pintag::replica {

using server::HttpRequest;

bool ChangesRegistry(const server::Route& route) {
  return route.access == server::Access::kAdmin && route.method != "GET";
}

server::Router ReadOnlyRouter(const server::Router& router, const std::string& primary_url) {
  server::Router read_only;
  for (server::Route route : router.routes()) {
    if (ChangesRegistry(route)) {
      route.access = server::Access::kOpen;
      route.consumes.clear();
      // Refused before the body is read: a replica has no use for it, and reading it (up to
      // the body limit, from anyone, since no token is asked for) would only cost memory.
      route.answers_before_body = true;
      route.handler = [primary_url](const HttpRequest& request) {
        return server::ProblemResponse(
            {403, "Read-Only Replica",
             "this server is a read-only replica of the registry; send " + request.method + " " +
                 request.path.substr(0, 200) + " to the primary" +
                 (primary_url.empty() ? " (this replica was not told which: start it with "
                                        "--primary URL)"
                                      : " at " + primary_url),
             "about:blank"});
      };
      route.summary += " (a replica refuses it: send it to the primary)";
    }
    read_only.add(std::move(route));
  }
  return read_only;
}

}  // namespace pintag::replica
