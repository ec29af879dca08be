// GET /api/v1/registry and GET /api/v1/registry/snapshot: which registry version a server
// serves, and the primary's snapshot for its read-only replicas (docs/SCALING.md).

#include "app/routes.hpp"
#include "pintag/db/snapshot.hpp"
#include "replica/snapshot_follower.hpp"

namespace pintag::app {

HttpResponse GetRegistryStatus(const AppContext& context, const HttpRequest& /*request*/) {
  db::Result<std::int64_t> version = db::Result<std::int64_t>(0);
  {
    auto connection = context.pool->acquire();
    version = db::RegistryVersion(*connection);
  }
  if (!version) throw HttpError(503, "the registry is not readable");
  json body = {{"registry_version", *version}, {"role", context.read_only ? "replica" : "primary"}};
  body["primary"] = context.read_only ? json(context.primary_url) : json(nullptr);
  return HttpResponse::Json(body.dump());
}

HttpResponse GetRegistrySnapshot(const AppContext& context, const HttpRequest& request) {
  if (!context.publisher) {
    throw HttpError(404,
                    "this server publishes no snapshot (a primary does when started with "
                    "--snapshot FILE)");
  }
  const db::Result<std::int64_t> live = context.publisher->liveVersion();
  if (!live) throw HttpError(503, "the live database is not readable");
  if (request.header("If-None-Match") == replica::VersionETag(*live)) {
    HttpResponse not_modified = HttpResponse::Bytes("application/vnd.sqlite3", "", 304);
    not_modified.headers.emplace_back("ETag", replica::VersionETag(*live));
    return not_modified;
  }
  db::Result<replica::PublishedSnapshot> published = context.publisher->read();
  if (!published) throw HttpError(503, "no snapshot could be published; see the server's log");
  const std::int64_t version = published->info.registry_version;
  HttpResponse response =
      HttpResponse::Bytes("application/vnd.sqlite3", std::move(published.value().bytes));
  response.headers.emplace_back("ETag", replica::VersionETag(version));
  response.headers.emplace_back("Cache-Control", "no-cache");
  return response;
}

}  // namespace pintag::app
