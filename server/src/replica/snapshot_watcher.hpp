#pragma once
// A read-only replica's side of a snapshot file: notices when another file was put at its path
// (renamed into place by `pintag snapshot --out`, or by the follower), checks that file is a whole
// snapshot, and then hands it on with `on_loaded`. A damaged or foreign file is reported once
// and ignored: the replica goes on serving the snapshot it has.

#include <sys/types.h>

#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "pintag/db/snapshot.hpp"

namespace pintag::replica {

class SnapshotWatcher {
 public:
  using OnLoaded = std::function<void(const db::SnapshotInfo&)>;

  /// `loaded`: the snapshot already served from `path` (verified by the caller).
  SnapshotWatcher(std::string path, db::SnapshotInfo loaded, OnLoaded on_loaded);
  ~SnapshotWatcher();  ///< stops the thread
  SnapshotWatcher(const SnapshotWatcher&) = delete;
  SnapshotWatcher& operator=(const SnapshotWatcher&) = delete;

  /// Looks at the file now (SIGHUP, or the follower installed one); true when a new snapshot
  /// was loaded.
  bool check();
  /// Checks every `interval` on a thread of its own, until destroyed.
  void start(std::chrono::milliseconds interval);

  /// The snapshot being served.
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

  std::string path_;
  OnLoaded on_loaded_;
  mutable std::mutex mutex_;  // one check at a time; guards the fields below
  db::SnapshotInfo loaded_;
  std::optional<Identity> seen_;  // the file last looked at, loaded or refused
  std::mutex stop_mutex_;
  std::condition_variable stop_changed_;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace pintag::replica
