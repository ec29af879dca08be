#pragma once
// The PinTag application assembled: every /api/v1 route of the route table over one database,
// bearer tokens verified against its token table, readiness from the database file, the
// metrics. `pintag serve` builds this and hands it to server::HttpServer.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "app/connection_pool.hpp"
#include "app/scan_log_writer.hpp"
#include "pintag/server/api.hpp"
#include "replica/follow_status.hpp"
#include "replica/snapshot_publisher.hpp"

namespace pintag::app {

struct AppConfig {
  std::string db_path;                                        ///< an existing, migrated database
  std::optional<std::filesystem::path> web_dir;               ///< static files; none = none
  std::size_t max_body_bytes = server::kDefaultMaxBodyBytes;  ///< 25 MiB
  std::int64_t max_pixels = 40'000'000;                       ///< decoded pixels per photo
  std::int64_t max_pixels_in_flight = 80'000'000;  ///< photos and PNGs at once, all requests
  std::size_t max_batch = 100;                     ///< labels per POST /labels
  int max_tag_px = 4096;                           ///< largest tag PNG square side
  int busy_timeout_ms = 5000;                      ///< SQLite lock wait
  int worker_threads = 4;  ///< the server's; writers may hold half of them (WriteGate)
  /// A read-only replica (issue 22): db_path is a snapshot, reloaded through `pool`; writes
  /// answer 403 naming primary_url (empty: not told which); scans go to scan_log_path.
  bool read_only = false;
  std::string primary_url;
  std::string scan_log_path;  ///< an existing scan log file (db::OpenScanLogFile); none = db_path
  std::shared_ptr<ConnectionPool> pool;  ///< connections to db_path; made here when not given
  /// A primary's snapshot for its replicas (GET /api/v1/registry/snapshot); none = no route.
  std::shared_ptr<replica::SnapshotPublisher> publisher;
  /// A following replica's polls, shown by GET /api/v1/registry (null: not following).
  std::shared_ptr<const replica::FollowStatus> follow_status;
  /// A read-only replica's word on the file it serves (written over in place?), asked by /readyz
  /// beside a query: damage can spare the pages one query reads. Empty: not asked.
  server::HealthCheck served_file_health;
};

/// The application, and what its server ends once serving is over.
struct App {
  std::shared_ptr<const server::Api> api;
  /// Writes the scan log; finish() it when serving ends, while a stop signal can still cut it
  /// short (ending the Api finishes it too).
  std::shared_ptr<ScanLogWriter> scan_log;
};

/// Builds the application. Throws std::runtime_error when the web dir does not exist.
App BuildApp(const AppConfig& config);
/// BuildApp's Api alone.
std::shared_ptr<const server::Api> BuildApi(const AppConfig& config);

/// Readiness of the database at `path`, as /readyz reports it: the same file (device and inode)
/// `pool` opened at start, a fresh connection to it (never created) and a real query on the
/// registry. Nothing when ready, else why not.
server::HealthCheck DatabaseHealthCheck(const std::string& path,
                                        std::shared_ptr<ConnectionPool> pool);

/// Readiness of a read-only replica: `served_file` finds nothing wrong (when given), and the
/// snapshot its pool opens now answers a query.
server::HealthCheck SnapshotHealthCheck(const std::shared_ptr<ConnectionPool>& pool,
                                        server::HealthCheck served_file = {});

}  // namespace pintag::app
