#pragma once
// A read-only replica that follows a primary: polls the primary's
// GET /api/v1/registry/snapshot with If-None-Match (the ETag of the snapshot it holds, when it
// fetched it in this run) and a replica token; a 200 carries another snapshot, which is checked
// and renamed into place at the replica's snapshot path (db::InstallSnapshot); a 304 means it is
// current. The ETag names the primary's run as well as the version, so a primary restored from a
// backup, whose versions count again from the backup's, is followed, not taken as current.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "pintag/db/result.hpp"
#include "pintag/db/snapshot.hpp"
#include "replica/file_identity.hpp"
#include "replica/follow_status.hpp"
#include "replica/periodic_thread.hpp"

namespace httplib {
class Client;
}

namespace pintag::replica {

struct FollowOptions {
  std::string primary_url;  ///< e.g. http://127.0.0.1:8090
  std::string token;        ///< a replica (or admin) token's secret
  /// The file `token` was read from (--follow-token-file), or empty: read again before a poll
  /// once the file at the path has changed, so a rotated token is taken without a signal.
  std::string token_file;
  std::string path;                  ///< where the replica's snapshot lives
  std::chrono::seconds timeout{30};  ///< per request to the primary
  /// A larger answer is refused as it arrives (the body is held in memory until installed; the
  /// seeded registry's snapshot is about 35 MB).
  std::size_t max_bytes = std::size_t{1} << 30;
};

class SnapshotFollower {
 public:
  using OnInstalled = std::function<void(const db::SnapshotInfo&)>;

  SnapshotFollower(FollowOptions options, OnInstalled on_installed);
  /// Cancels a download in progress (an install in progress finishes) and stops the thread: a
  /// primary that answers slowly, or not at all, held SIGTERM for the read timeout (30 s).
  ~SnapshotFollower();
  SnapshotFollower(const SnapshotFollower&) = delete;
  SnapshotFollower& operator=(const SnapshotFollower&) = delete;

  /// Asks the primary once. The installed snapshot when there was a newer one; nothing when the
  /// replica is current; an error (with the primary's answer) when the primary could not be
  /// reached, refused the token or sent something that is not a whole snapshot. A primary
  /// sending as many snapshots as it will at once gives nothing, and deferred() is then true.
  db::Result<std::optional<db::SnapshotInfo>> fetch(std::optional<std::int64_t> have);
  bool deferred() const { return deferred_; }
  /// The primary answered the last fetch with 200 or 304, whatever was then made of it (a
  /// snapshot refused for its keys or cut short is still an answer).
  bool primaryAnswered() const { return primary_answered_; }

  /// The registry version the replica serves now (nothing before its first snapshot).
  using Have = std::function<std::optional<std::int64_t>()>;
  /// Polls every `interval` on a thread of its own, until destroyed, telling `status` how each
  /// poll went (may be null).
  void start(Have have, std::chrono::milliseconds interval,
             std::shared_ptr<FollowStatus> status = nullptr);
  /// The token for the next poll (SIGHUP re-reads --follow-token-file); true when it differs
  /// from the one in use.
  bool setToken(std::string token);
  /// The token for a poll: options_.token, read again from `token_file` when the file changed.
  std::string pollToken();

 private:
  FollowOptions options_;
  OnInstalled on_installed_;
  std::mutex client_mutex_;  // guards client_, options_.token and token_file_seen_
  /// The token file as last looked at before a read, to tell when it changed; nothing until the
  /// first poll looks (the token given was read before it).
  std::optional<FileIdentity> token_file_seen_;
  /// Set before the client is stopped, and read where the client makes its socket: a stop()
  /// before the request is in flight does nothing in cpp-httplib 0.11, so the socket is shut
  /// there instead (never under client_mutex_, which stop() may hold while it waits).
  std::atomic<bool> stopping_{false};
  /// The last fetch was told to come back later (SnapshotPublisher::kBusyProblemType): the
  /// polling thread's own, so the follow status keeps its last real answer or failure.
  bool deferred_ = false;
  bool primary_answered_ = false;      ///< primaryAnswered(); the polling thread's own
  httplib::Client* client_ = nullptr;  ///< the download in progress, to cancel
  /// The ETag and version of the last snapshot installed (the fetching thread's own).
  std::string installed_etag_;
  std::int64_t installed_version_ = -1;
  /// A snapshot refused for what it holds (it does not keep the keys served), and why: not
  /// fetched again while the primary still serves it, and the refusal stands meanwhile.
  std::string refused_etag_;
  db::Error refused_error_{db::ErrorCode::kConflict, ""};
  /// A snapshot downloaded whole and then not installed (a full disk, a directory it cannot
  /// write, a body over max_bytes) is not downloaded again before a delay that doubles with each
  /// such failure in a row: a replica re-fetched 35 MB every poll, holding one of the primary's
  /// two snapshot slots each time. Polls meanwhile give the last error without asking.
  static constexpr std::chrono::seconds kMaxDownloadDelay{60};
  int download_failures_ = 0;
  std::chrono::steady_clock::time_point next_download_;
  db::Error download_error_{db::ErrorCode::kStorage, ""};
  db::Error downloadWasted(db::Error error);
  PeriodicThread thread_;  // last: stopped before the members it uses go
};

/// The ETag of a registry version published by a primary run of `epoch`
/// (SnapshotPublisher::epoch): "<version>-<epoch>", quoted.
std::string RegistryETag(std::int64_t version, const std::string& epoch);

}  // namespace pintag::replica
