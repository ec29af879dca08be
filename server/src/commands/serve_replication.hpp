#pragma once
// `pintag serve`'s part in a scaled-out registry (docs/SCALING.md): a primary that publishes
// snapshots (--snapshot FILE), or a read-only replica serving a snapshot (--read-only), reloading
// it when a newer one is put in place or on SIGHUP, and pulling newer ones from its primary
// (--follow URL, token in PINTAG_FOLLOW_TOKEN or --follow-token-file).

#include <CLI/CLI.hpp>
#include <memory>
#include <optional>
#include <string>

#include "app/app.hpp"
#include "replica/snapshot_follower.hpp"
#include "replica/snapshot_publisher.hpp"
#include "replica/snapshot_watcher.hpp"

namespace pintag::cli {

struct ReplicationArgs {
  bool read_only = false;
  std::string follow;             ///< primary URL to pull snapshots from
  std::string follow_token_file;  ///< file holding the replica token (else PINTAG_FOLLOW_TOKEN)
  std::optional<int> follow_interval_ms;  ///< when given; only a following replica takes it
  int followIntervalMs() const { return follow_interval_ms.value_or(1000); }
  std::string primary;   ///< named in refusals of writes (default: the --follow URL)
  std::string scan_log;  ///< a replica's own scan log (default: <db stem>-scans.db beside it)
  std::string snapshot;  ///< a primary publishes its snapshot here
};

void AddReplicationOptions(CLI::App* serve, ReplicationArgs& args);

/// The replication options that contradict each other or the role, checked before the database
/// is opened or seeded: a replica's options (--scan-log, --primary, --follow-token-file) on a
/// primary, --follow-token-file and --follow-interval-ms on a server that follows no one, and a
/// --snapshot that names the database or one of its files. UsageError.
void CheckReplicationArgs(const ReplicationArgs& args, const std::string& db_path);

class Replication {
 public:
  /// Prepares before the server is built: a following replica without a usable snapshot fetches
  /// one (waiting for the primary), a replica checks its snapshot and opens its scan log, a
  /// publishing primary writes its first snapshot. Fills the replication fields of `config`.
  /// Throws UsageError or std::runtime_error.
  Replication(const ReplicationArgs& args, app::AppConfig& config);
  ~Replication();
  Replication(const Replication&) = delete;
  Replication& operator=(const Replication&) = delete;

  bool readOnly() const { return args_.read_only; }
  /// Starts the watcher, follower and publisher threads (once the port is bound).
  void start();
  /// SIGHUP: look at the snapshot file now, and re-read a follower's token.
  void reload();
  /// One line for the start banner.
  std::string describe() const;

 private:
  ReplicationArgs args_;
  std::string db_path_;
  std::shared_ptr<app::ConnectionPool> pool_;
  std::string token_;
  std::shared_ptr<replica::SnapshotPublisher> publisher_;
  std::unique_ptr<replica::SnapshotWatcher> watcher_;
  std::shared_ptr<replica::FollowStatus> follow_status_;
  std::unique_ptr<replica::SnapshotFollower> follower_;
};

}  // namespace pintag::cli
