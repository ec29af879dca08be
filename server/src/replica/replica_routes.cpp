#include "replica/replica_routes.hpp"

#include <nlohmann/json.hpp>

#include "pintag/server/problem.hpp"
#include "replica/snapshot_follower.hpp"

namespace pintag::replica {

using server::HttpRequest;
using server::HttpResponse;

void AddSnapshotRoute(server::Router& router, const std::shared_ptr<SnapshotPublisher>& publisher) {
  server::Route route = server::MakeRoute(
      "GET", "/api/v1/registry/snapshot", server::Access::kReplica,
      [publisher](const HttpRequest& request) {
        const db::Result<std::int64_t> live = publisher->liveVersion();
        if (!live) throw server::HttpError(503, "the live database is not readable");
        if (request.header("If-None-Match") == VersionETag(*live)) {
          HttpResponse not_modified = HttpResponse::Bytes("application/vnd.sqlite3", "", 304);
          not_modified.headers.emplace_back("ETag", VersionETag(*live));
          return not_modified;
        }
        db::Result<PublishedSnapshot> published = publisher->read();
        if (!published) {
          throw server::HttpError(503, "no snapshot could be published; see the server's log");
        }
        const std::int64_t version = published->info.registry_version;
        HttpResponse response =
            HttpResponse::Bytes("application/vnd.sqlite3", std::move(published.value().bytes));
        response.headers.emplace_back("ETag", VersionETag(version));
        response.headers.emplace_back("Cache-Control", "no-cache");
        return response;
      },
      "The registry as an SQLite snapshot for read-only replicas (ETag: its registry version)",
      "replication");
  route.produces = {"application/vnd.sqlite3"};
  router.add(std::move(route));
}

void AddRegistryStatusRoute(server::Router& router, RegistryStatus status) {
  router.add(server::MakeRoute(
      "GET", "/api/v1/registry", server::Access::kOpen,
      [status](const HttpRequest&) {
        const db::Result<std::int64_t> version = status.version();
        if (!version) throw server::HttpError(503, "the registry is not readable");
        nlohmann::json body = {{"registry_version", *version}, {"role", status.role}};
        body["primary"] = status.primary_url ? nlohmann::json(*status.primary_url) : nullptr;
        return HttpResponse::Json(body.dump());
      },
      "Which registry version this server serves, and whether it is the primary or a replica",
      "replication"));
}

bool ChangesRegistry(const server::Route& route) {
  return route.access == server::Access::kAdmin && route.method != "GET";
}

server::Router ReadOnlyRouter(const server::Router& router, const std::string& primary_url) {
  server::Router read_only;
  for (server::Route route : router.routes()) {
    if (ChangesRegistry(route)) {
      route.access = server::Access::kOpen;
      route.consumes.clear();
      route.handler = [primary_url](const HttpRequest& request) {
        return server::ProblemResponse(
            {403, "Read-Only Replica",
             "this server is a read-only replica of the registry; send " + request.method + " " +
                 request.path.substr(0, 200) + " to the primary at " + primary_url,
             "about:blank"});
      };
      route.summary += " (a replica refuses it: send it to the primary)";
    }
    read_only.add(std::move(route));
  }
  return read_only;
}

}  // namespace pintag::replica
