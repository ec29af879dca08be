// GET /api/v1/registry and GET /api/v1/registry/snapshot: which registry version a server
// serves, and the primary's snapshot for its read-only replicas (docs/SCALING.md).

#include <algorithm>
#include <chrono>
#include <ctime>
#include <optional>
#include <string>
#include <string_view>

#include "app/entity_tags.hpp"
#include "app/routes.hpp"
#include "pintag/db/snapshot.hpp"
#include "replica/snapshot_follower.hpp"
#include "replica/snapshot_publisher.hpp"

namespace pintag::app {
namespace {

/// "2026-12-05T23:50:01Z", as the registry's own timestamps read.
std::string UtcTimestamp(std::chrono::system_clock::time_point t) {
  const std::time_t seconds = std::chrono::system_clock::to_time_t(t);
  std::tm utc{};
  ::gmtime_r(&seconds, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

}  // namespace

HttpResponse GetRegistryStatus(const AppContext& context, const HttpRequest& /*request*/) {
  db::Result<std::int64_t> version = db::Result<std::int64_t>(0);
  {
    auto connection = context.pool->acquire();
    version = db::RegistryVersion(*connection);
  }
  if (!version) throw HttpError(503, "the registry is not readable");
  json body = {{"registry_version", *version}, {"role", context.read_only ? "replica" : "primary"}};
  body["primary"] =
      context.read_only && !context.primary_url.empty() ? json(context.primary_url) : json(nullptr);
  if (context.follow_status) {
    const replica::FollowStatus::View follow = context.follow_status->view();
    const auto when = [](const std::optional<replica::FollowStatus::Clock::time_point>& t) {
      return t ? json(UtcTimestamp(*t)) : json(nullptr);
    };
    body["follow"] = {{"last_answer", when(follow.last_answer)},
                      {"error", follow.error.empty() ? json(nullptr) : json(follow.error)},
                      {"failing_since", when(follow.failing_since)}};
  }
  if (context.publisher) {
    // What replicas can be given: the snapshot kept for them, and why it lags when it does.
    const replica::SnapshotPublisher::Status published = context.publisher->status();
    body["snapshot"] = {
        {"published_version",
         published.published_version ? json(*published.published_version) : json(nullptr)},
        {"error", published.error.empty() ? json(nullptr) : json(published.error)},
        {"failing_since",
         published.failing_since ? json(UtcTimestamp(*published.failing_since)) : json(nullptr)}};
  }
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
  const std::optional<EntityTagList> none_match = EntityTagsHeader(request, "If-None-Match");
  const std::string& epoch = context.publisher->epoch();
  // "<version>" alone is what followers before the epoch send: still current for them, so that
  // during a rolling upgrade they are not sent the whole registry on every poll.
  // Appended, not `"\"" + ...`: GCC 12 warns (-Wrestrict) about that concatenation wrongly.
  std::string version_only = "\"";
  version_only += std::to_string(*live);
  version_only += '"';
  if (none_match && (NoneMatchNames(*none_match, replica::RegistryETag(*live, epoch)) ||
                     NoneMatchNames(*none_match, version_only))) {
    // "Content-Length: 0" (cpp-httplib's) stays: a replica's cpp-httplib client reads the 200's
    // length, which RFC 9110 (8.6) would rather see here, as a body to wait for (GetSortPlan).
    HttpResponse not_modified = HttpResponse::Bytes("application/vnd.sqlite3", "", 304);
    not_modified.headers.emplace_back("ETag", replica::RegistryETag(*live, epoch));
    return not_modified;
  }
  const std::optional<replica::SnapshotPublisher::ReaderSlot> slot = context.publisher->tryReader();
  if (!slot) {
    return server::ProblemResponse(
        {503, "Snapshots Busy",
         std::to_string(replica::SnapshotPublisher::kMaxSnapshotReaders) +
             " snapshots are being prepared; ask again in a second (the worker threads stay free "
             "for other requests)",
         std::string(replica::SnapshotPublisher::kBusyProblemType), /*retry_after_seconds=*/1});
  }
  db::Result<replica::PublishedSnapshot> published = context.publisher->read();
  if (!published) {
    // Answered, not thrown: a thrown 5xx is logged as a server error, one line a replica poll
    // (two a second with two replicas), where the publisher logs each failed try already.
    return server::ProblemResponse(503,
                                   "no snapshot could be published: " + published.error().message);
  }
  const std::int64_t version = published->info.registry_version;
  HttpResponse response =
      HttpResponse::Bytes("application/vnd.sqlite3", std::move(published.value().bytes));
  response.headers.emplace_back("ETag", replica::RegistryETag(version, epoch));
  response.headers.emplace_back("Cache-Control", "no-cache");
  return response;
}

}  // namespace pintag::app
