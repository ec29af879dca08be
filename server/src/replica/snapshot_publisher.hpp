#pragma once
// The primary's side of registry snapshots: keeps one snapshot file of the live database current.
// A background thread republishes after every change to the registry version, whoever made it
// (the API, `pintag import`, `pintag token`); a request for the snapshot republishes first when
// the live version moved since, so a replica never gets a snapshot older than a write that
// already returned.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

#include "pintag/db/result.hpp"
#include "pintag/db/snapshot.hpp"
#include "pintag/db/sqlite.hpp"
#include "replica/file_identity.hpp"
#include "replica/periodic_thread.hpp"

namespace pintag::replica {

/// A published snapshot's bytes and what they hold.
struct PublishedSnapshot {
  db::SnapshotInfo info;
  std::string bytes;
};

class SnapshotPublisher {
 public:
  /// `live_path`: the primary's database (must exist); `out_path`: the snapshot file it keeps.
  SnapshotPublisher(std::string live_path, std::string out_path);
  ~SnapshotPublisher() = default;  ///< stops the thread
  SnapshotPublisher(const SnapshotPublisher&) = delete;
  SnapshotPublisher& operator=(const SnapshotPublisher&) = delete;

  /// The live database's registry version now; never waits for a publication in progress
  /// (its own connection), so a replica that is current gets its 304 at once.
  db::Result<std::int64_t> liveVersion();

  /// At most kMaxSnapshotReaders whole snapshots are answered at once: each holds a worker
  /// thread while a publication takes seconds, and replicas that all asked after one change took
  /// every worker (the primary's /readyz waited 6 s). A held slot; empty when all are taken.
  class ReaderSlot {
   public:
    explicit ReaderSlot(std::atomic<int>* count) : count_(count) {}
    ReaderSlot(ReaderSlot&& other) noexcept : count_(std::exchange(other.count_, nullptr)) {}
    ReaderSlot(const ReaderSlot&) = delete;
    ReaderSlot& operator=(const ReaderSlot&) = delete;
    ReaderSlot& operator=(ReaderSlot&&) = delete;
    ~ReaderSlot() {
      if (count_ != nullptr) --*count_;
    }

   private:
    std::atomic<int>* count_;
  };
  static constexpr int kMaxSnapshotReaders = 2;
  /// The problem type of the 503 a primary answers while kMaxSnapshotReaders snapshots are being
  /// sent: a follower asks again at its next poll and counts it neither as an answer nor as a
  /// failure. Any other 503 (a database busy or replaced, one that cannot be read) is a failure,
  /// so a replica whose primary stays unable to send reports it.
  static constexpr std::string_view kBusyProblemType = "tag:pintag,2026:snapshot-readers-busy";
  std::optional<ReaderSlot> tryReader();
  /// Random per publisher, so per primary run: a version counts changes within one database's
  /// history only, and a primary restored from a backup counts again from the backup's version,
  /// to the same numbers with other rows. The ETag names both (RegistryETag), so replicas take
  /// the first snapshot of every run whatever its version.
  const std::string& epoch() const { return epoch_; }
  /// The snapshot of the live version (published first if it is not yet), with its bytes.
  db::Result<PublishedSnapshot> read();
  /// Publishes when the live version differs from the published one; the published info.
  db::Result<db::SnapshotInfo> publish();

  /// Checks every `interval` on a thread of its own, until destroyed.
  void start(std::chrono::milliseconds interval);

  using Clock = std::chrono::steady_clock;
  /// After a failed publication, the next is tried no sooner than this after it; the wait doubles
  /// with each failure in a row, up to kMaxRetryDelay. A whole snapshot tried every half second
  /// on a full disk took the writes' space (and 200 MB/s of writes) from the live database.
  static constexpr std::chrono::seconds kFirstRetryDelay{1};
  static constexpr std::chrono::seconds kMaxRetryDelay{60};

  struct Status {
    std::optional<std::int64_t> published_version;  ///< of the file kept now, if any
    std::string error;                              ///< the last publication's, when it failed
    std::optional<std::chrono::system_clock::time_point> failing_since;
  };
  /// Never waits for a publication in progress (a /metrics scrape asks).
  Status status() const;

 private:
  /// Publishes when needed, unless a failure's retry delay still runs; records the outcome.
  db::Result<db::SnapshotInfo> publishLocked();
  /// Writes the snapshot when the live version or the file changed; the published info.
  db::Result<db::SnapshotInfo> writeIfChanged();
  /// Records a failed publication (its retry delay, the status, the log line); the error, saying
  /// how many failed in a row and when the next try is.
  db::Error failed(db::Error error);
  /// The published file is still the one written: a file removed or replaced by someone else is
  /// published again (it was served as it was, or the route answered 503, until the next write).
  bool publishedFileIsOurs() const;

  void updateStatus();  ///< status_ from what mutex_ guards; called holding mutex_

  std::string live_path_;
  std::string out_path_;
  std::string epoch_;
  std::mutex mutex_;  // guards the connection, published_ and the file's replacement
  std::optional<db::Connection> live_;
  std::mutex version_mutex_;  // guards version_connection_
  std::optional<db::Connection> version_connection_;
  std::atomic<int> readers_{0};
  std::optional<db::SnapshotInfo> published_;
  std::optional<FileIdentity> published_file_;
  std::optional<db::Error> failure_;  // the last publication's, while they fail
  int failures_in_a_row_ = 0;
  Clock::time_point retry_at_{};
  std::optional<std::chrono::system_clock::time_point> failing_since_;
  mutable std::mutex status_mutex_;  // guards status_, so that reading it never waits on mutex_
  Status status_;
  PeriodicThread thread_;  // last: stopped before the members it uses go
};

}  // namespace pintag::replica
