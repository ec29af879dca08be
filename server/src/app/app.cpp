#include "app/app.hpp"

#include <sys/stat.h>

#include <chrono>
#include <vector>

#include "app/context.hpp"
#include "app/db_problems.hpp"
#include "app/route_table.hpp"
#include "pintag/db/database.hpp"
#include "pintag/db/snapshot.hpp"
#include "pintag/db/tokens.hpp"
#include "replica/replica_routes.hpp"

namespace pintag::app {
namespace {

server::Access Granted(db::Role role) {
  switch (role) {
    case db::Role::kAdmin:
      return server::Access::kAdmin;
    case db::Role::kCounter:
      return server::Access::kCounter;
    case db::Role::kReplica:
      return server::Access::kReplica;
    case db::Role::kScanner:
      break;
  }
  return server::Access::kScanner;
}

server::TokenVerifier RegistryTokenVerifier(const std::shared_ptr<ConnectionPool>& pool) {
  // A token that cannot be checked is not a wrong token: a busy or unreachable database answers
  // 503 (acquire() and ThrowDbError throw it), so a client does not drop a good token over an
  // outage.
  return [pool](std::string_view secret) -> std::optional<server::Principal> {
    auto connection = pool->acquire();
    auto token = db::VerifyToken(*connection, secret);
    if (!token) {
      if (token.error().code == db::ErrorCode::kUnauthorized) return std::nullopt;
      ThrowDbError(token.error());
    }
    return server::Principal{std::to_string(token->id), Granted(token->role)};
  };
}

void DefineCounters(server::Metrics& metrics) {
  metrics.defineCounter(kLabelsRenderedCounter, "Labels rendered (PDF pages, PNGs, SVGs).");
  metrics.defineCounter(kTagsRenderedCounter, "Tag images rendered.");
  metrics.defineCounter(kScansCounter,
                        "POST /api/v1/detect uploads the scan log records: photos read, and "
                        "uploads refused as not an image or too large.");
  metrics.defineCounter(kScanLogFailuresCounter,
                        "Scans answered but not written to the scan log (the error is logged).");
  metrics.defineCounter(kDetectionsCounter, "Tags decoded in uploaded photos.");
  metrics.defineCounter(kUnknownKeysCounter, "Decoded tags whose key no pincode holds.");
  metrics.defineCounter(kPixelBudgetWaitsCounter,
                        "Photos and PNGs that waited for room under --max-pixels-in-flight.");
}

/// A following replica's polls as gauges, so that an alert can fire on a replica that serves an
/// old snapshot while it stays ready (GET /api/v1/registry says the same to a person).
void AddFollowGauges(server::Metrics& metrics,
                     std::shared_ptr<const replica::FollowStatus> follow_status) {
  metrics.addGaugeSource([follow_status = std::move(follow_status)] {
    const replica::FollowStatus::View view = follow_status->view();
    const auto seconds = [](replica::FollowStatus::Clock::time_point t) {
      return std::chrono::duration<double>(t.time_since_epoch()).count();
    };
    std::vector<server::Metrics::Gauge> gauges;
    gauges.push_back({"pintag_follow_failing",
                      "1 while this replica's polls of its primary fail, else 0.",
                      view.failing_since ? 1.0 : 0.0});
    if (view.last_answer) {
      gauges.push_back({"pintag_follow_last_answer_timestamp_seconds",
                        "When the primary last answered a poll (200 or 304), Unix time.",
                        seconds(*view.last_answer)});
    }
    if (view.failing_since) {
      gauges.push_back({"pintag_follow_failing_since_timestamp_seconds",
                        "When this replica's polls began to fail, Unix time.",
                        seconds(*view.failing_since)});
    }
    return gauges;
  });
}

/// A primary's snapshot publication as gauges: replicas keep serving an older registry while it
/// fails, and the primary stays ready (GET /api/v1/registry says why).
void AddPublishGauges(server::Metrics& metrics,
                      std::shared_ptr<replica::SnapshotPublisher> publisher) {
  metrics.addGaugeSource([publisher = std::move(publisher)] {
    const replica::SnapshotPublisher::Status status = publisher->status();
    std::vector<server::Metrics::Gauge> gauges = {
        {"pintag_snapshot_publish_failing",
         "1 while this primary's snapshot for its replicas cannot be published, else 0.",
         status.failing_since ? 1.0 : 0.0}};
    if (status.published_version) {
      gauges.push_back({"pintag_snapshot_published_version",
                        "The registry version of the snapshot this primary gives its replicas.",
                        static_cast<double>(*status.published_version)});
    }
    return gauges;
  });
}

/// The registry version served, read at each scrape (a one-row query): a replica's below its
/// primary's for long is one that does not follow, whatever its other gauges say.
void AddRegistryVersionGauge(server::Metrics& metrics, std::weak_ptr<ConnectionPool> pool) {
  metrics.addGaugeSource([pool = std::move(pool)] {
    std::vector<server::Metrics::Gauge> gauges;
    const auto alive = pool.lock();
    if (!alive) return gauges;
    try {
      auto connection = alive->acquire();
      const db::Result<std::int64_t> version = db::RegistryVersion(*connection);
      if (version) {
        gauges.push_back({"pintag_registry_version",
                          "The registry version this server serves (GET /api/v1/registry).",
                          static_cast<double>(*version)});
      }
    } catch (const std::exception&) {
      // Unreadable: left out, as /readyz says why.
    }
    return gauges;
  });
}

/// The scans waiting for the scan log (app/scan_log_writer.hpp): above zero while the log's lock is
/// held elsewhere. Weak: the writer holds the metrics, and must end with the context.
void AddScanLogGauge(server::Metrics& metrics, std::weak_ptr<const ScanLogWriter> writer) {
  metrics.addGaugeSource([writer = std::move(writer)] {
    std::vector<server::Metrics::Gauge> gauges;
    if (const auto alive = writer.lock()) {
      gauges.push_back({"pintag_scan_log_backlog",
                        "Scans answered and waiting to be written to the scan log.",
                        static_cast<double>(alive->backlog())});
    }
    return gauges;
  });
}

/// The pixel budget (--max-pixels-in-flight) as gauges: what it holds now and the most it has held,
/// to size the budget against the memory a server has (about 7 bytes a pixel).
void AddPixelBudgetGauges(server::Metrics& metrics, std::shared_ptr<const PixelBudget> budget) {
  metrics.addGaugeSource([budget = std::move(budget)] {
    return std::vector<server::Metrics::Gauge>{
        {"pintag_pixel_budget_held_pixels",
         "Pixels of photos and PNGs held under --max-pixels-in-flight now (an overlay counts "
         "twice).",
         static_cast<double>(budget->held())},
        {"pintag_pixel_budget_peak_pixels",
         "The most pixels held under --max-pixels-in-flight at once since the server started.",
         static_cast<double>(budget->peak())}};
  });
}

}  // namespace

// /readyz is open: its answers say what is wrong without the --db path (the operator knows it),
// as the storage problems of db_problems.cpp keep file names to the log.
server::HealthCheck DatabaseHealthCheck(const std::string& path,
                                        std::shared_ptr<ConnectionPool> pool) {
  return [path, pool = std::move(pool)]() -> std::optional<std::string> {
    // The pool knows the file it opened; asking it is also how it learns, when no request comes,
    // that the file left (and empties its log).
    if (!pool->servesFileAtPath()) {
      struct stat now {};
      if (::stat(path.c_str(), &now) != 0) return "database unreachable: its file is missing";
      return "database unreachable: its file was replaced since the server started (restart it "
             "to use the new file)";
    }
    try {
      db::ConnectionOptions options;
      options.create = false;
      options.busy_timeout_ms = 1000;
      db::Connection connection(path, options);
      if (connection.queryInt64("PRAGMA user_version") != db::kSchemaVersion)
        return "database unreachable: it has an unexpected schema version";
      connection.queryInt64("SELECT count(*) FROM (SELECT 1 FROM tag_keys LIMIT 1)");
    } catch (const std::exception& e) {
      std::string why = e.what();  // SQLite's reason, without the path an open error names
      for (std::size_t at = 0; (at = why.find(path, at)) != std::string::npos;) {
        why.replace(at, path.size(), "the file");
      }
      return "database unreachable: " + why;
    }
    return std::nullopt;
  };
}

server::HealthCheck SnapshotHealthCheck(const std::shared_ptr<ConnectionPool>& pool,
                                        server::HealthCheck served_file) {
  return [pool, served_file = std::move(served_file)]() -> std::optional<std::string> {
    if (served_file) {
      if (std::optional<std::string> problem = served_file()) return problem;
    }
    try {
      auto connection = pool->acquire();
      const db::Result<std::int64_t> version = db::RegistryVersion(*connection);
      if (!version) return "snapshot unreadable: " + version.error().message;
      connection->queryInt64("SELECT count(*) FROM (SELECT 1 FROM tag_keys LIMIT 1)");
    } catch (const std::exception& e) {
      return std::string("snapshot unreadable: ") + e.what();
    }
    return std::nullopt;
  };
}

App BuildApp(const AppConfig& config) {
  auto context = std::make_shared<AppContext>();
  context->pool = config.pool ? config.pool
                              : std::make_shared<ConnectionPool>(
                                    config.db_path, config.busy_timeout_ms, config.read_only);
  context->metrics = std::make_shared<server::Metrics>();
  context->scan_log = std::make_shared<ScanLogWriter>(
      config.scan_log_path.empty()
          ? context->pool
          : std::make_shared<ConnectionPool>(config.scan_log_path, config.busy_timeout_ms),
      context->metrics, std::string(kScanLogFailuresCounter));
  context->max_pixels = config.max_pixels;
  context->pixel_budget = std::make_shared<PixelBudget>(config.max_pixels_in_flight);
  context->write_gate = std::make_shared<WriteGate>(WriteGateCapacity(config.worker_threads));
  context->max_batch = config.max_batch;
  context->max_tag_px = config.max_tag_px;
  context->read_only = config.read_only;
  context->primary_url = config.primary_url;
  context->publisher = config.publisher;
  context->follow_status = config.follow_status;
  DefineCounters(*context->metrics);
  AddScanLogGauge(*context->metrics, context->scan_log);
  AddPixelBudgetGauges(*context->metrics, context->pixel_budget);
  if (config.follow_status) AddFollowGauges(*context->metrics, config.follow_status);
  if (config.publisher) AddPublishGauges(*context->metrics, config.publisher);
  AddRegistryVersionGauge(*context->metrics, context->pool);
  server::Router router = AppRouter(context);
  if (config.read_only) router = replica::ReadOnlyRouter(router, config.primary_url);

  server::ApiOptions options;
  options.max_body_bytes = config.max_body_bytes;
  options.web_dir = config.web_dir;
  options.info.description =
      "PinTag labels, detection, registry and routing. Errors are application/problem+json "
      "(RFC 9457). Roles: admin (everything), counter (labels), scanner (detect), replica (the "
      "registry snapshot, for read-only replicas); lookups are open.";
  // A replica's file is replaced by design; its readiness is the snapshot it serves now.
  server::HealthCheck health = config.read_only
                                   ? SnapshotHealthCheck(context->pool, config.served_file_health)
                                   : DatabaseHealthCheck(config.db_path, context->pool);
  return {
      std::make_shared<const server::Api>(std::move(router), RegistryTokenVerifier(context->pool),
                                          std::move(health), context->metrics, std::move(options)),
      context->scan_log};
}

std::shared_ptr<const server::Api> BuildApi(const AppConfig& config) {
  return BuildApp(config).api;
}

}  // namespace pintag::app
