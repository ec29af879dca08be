#pragma once
// A read-only replica's side of its snapshot file: notices when another file was put at the path
// (renamed into place by `pintag snapshot --out`, or by the follower), checks it is a whole
// snapshot, and hands it on. What is served is a hard link to the file that was checked
// (`<path>.serving-N`), so a damaged file renamed into place later is never opened: it is
// reported once and ignored, and the replica goes on serving what it has.

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <string>

#include "pintag/db/snapshot.hpp"
#include "replica/periodic_thread.hpp"

namespace pintag::replica {

class SnapshotWatcher {
 public:
  /// Called with each newly loaded snapshot; its `path` is the file to open from now on.
  using OnLoaded = std::function<void(const db::SnapshotInfo&)>;

  /// Loads the snapshot at `path` (removing serving links a previous run left). Throws
  /// std::runtime_error when it is missing or not a whole snapshot.
  SnapshotWatcher(std::string path, OnLoaded on_loaded);
  ~SnapshotWatcher() = default;  ///< stops the thread; the serving link stays until the next start
  SnapshotWatcher(const SnapshotWatcher&) = delete;
  SnapshotWatcher& operator=(const SnapshotWatcher&) = delete;

  /// Looks at the file now (SIGHUP, or the follower installed one); true when a new snapshot
  /// was loaded.
  bool check();
  /// Checks every `interval` on a thread of its own, until destroyed.
  void start(std::chrono::milliseconds interval);

  /// The snapshot being served (its path is the serving link).
  db::SnapshotInfo loaded() const;

 private:
  struct Identity {
    dev_t device = 0;
    ino_t inode = 0;
    off_t size = 0;
    std::int64_t mtime_ns = 0;
    bool operator==(const Identity&) const = default;
  };
  static std::optional<Identity> Stat(const std::string& path);
  /// Links the file now at path_ to a new serving name and checks it; the error when it is not
  /// a whole snapshot. Requires mutex_.
  db::Result<db::SnapshotInfo> linkAndVerify();

  std::string path_;
  OnLoaded on_loaded_;
  mutable std::mutex mutex_;  // one check at a time; guards the fields below
  std::uint64_t links_made_ = 0;
  std::optional<db::SnapshotInfo> loaded_;
  std::optional<Identity> seen_;  // the file last looked at, loaded or refused
  PeriodicThread thread_;         // last: stopped before the members it uses go
};

}  // namespace pintag::replica
