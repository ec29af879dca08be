#pragma once
// A read-only replica's side of its snapshot file: notices when another file was put at the path
// (renamed into place by `pintag snapshot --out`, or by the follower), checks it is a whole
// snapshot, and hands it on. What is served is a hard link to the file that was checked
// (`<path>.serving-<process tag>-N`), so a damaged file renamed into place later is never opened:
// it is reported once and ignored, and the replica goes on serving what it has. So is a snapshot
// that does not keep the keys served; either refused file is kept as `<path>.refused` and the
// registry served is put back at the path.
//
// Several replicas may serve one file. Each names its links by a tag of its own and holds an
// exclusive lock on `<path>.serving-<tag>.lock` while it lives; a starting replica removes only
// the links whose lock nobody holds (a run that ended or crashed).

#include <chrono>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>

#include "pintag/db/snapshot.hpp"
#include "replica/file_identity.hpp"
#include "replica/periodic_thread.hpp"

namespace pintag::replica {

class SnapshotWatcher {
 public:
  /// Called with each newly loaded snapshot; its `path` is the file to open from now on.
  using OnLoaded = std::function<void(const db::SnapshotInfo&)>;

  /// Loads the snapshot at `path` (removing the serving links of runs that ended). Throws
  /// std::runtime_error when it is missing or not a whole snapshot, or its lock cannot be made.
  SnapshotWatcher(std::string path, OnLoaded on_loaded);
  /// Stops the thread, removes the serving link (connections still open keep reading the
  /// unlinked file) and the lock file, and releases the lock.
  ~SnapshotWatcher();
  SnapshotWatcher(const SnapshotWatcher&) = delete;
  SnapshotWatcher& operator=(const SnapshotWatcher&) = delete;

  /// Looks at the file now (SIGHUP, or the follower installed one); true when a new snapshot
  /// was loaded.
  bool check();
  /// Checks every `interval` on a thread of its own, until destroyed.
  void start(std::chrono::milliseconds interval);

  /// The snapshot being served (its path is the serving link).
  db::SnapshotInfo loaded() const;
  /// The registry version served, for a follower's If-None-Match; nothing while the file served
  /// was written over in place and no longer reads as a snapshot, or while no file is at the
  /// path (removed), so that the follower asks for the whole snapshot again instead of being
  /// told it is current.
  std::optional<std::int64_t> servedVersion() const;
  /// Why the registry served is not to be trusted now (its file was written over in place and no
  /// longer reads as a snapshot: some queries fail while others still answer), or nothing.
  std::optional<std::string> servedDamage() const;

 private:
  /// `<path>.serving-<tag><suffix>`: every name of a tag's files (links "-N", ".lock").
  std::string servingName(const std::string& tag, std::string_view suffix) const;
  /// Makes this process's tag and holds its lock file.
  void takeTag();
  /// Removes the lock file and lets the lock go.
  void releaseTag();
  /// Removes the links and lock files of tags whose lock nobody holds.
  void removeEndedRuns() const;
  /// Links the file now at path_ to a new serving name and checks it; the error when it is not
  /// a whole snapshot. `linked` is the identity of the file linked, even when refused;
  /// `link_made` the link's name, when one was made (the caller removes a refused one). Requires
  /// mutex_.
  db::Result<db::SnapshotInfo> linkAndVerify(std::optional<FileIdentity>* linked,
                                             std::string* link_made);
  /// After a refusal: keeps the refused file (its serving link `refused_link`, when it was
  /// linked) as `<path>.refused`, and puts the registry served back at the path, so that a
  /// restart or another replica on the path serves it too. What was done, for the log line.
  /// Requires mutex_.
  std::string putBackServed(const std::string& refused_link);

  std::string path_;
  OnLoaded on_loaded_;
  std::string tag_;           // this process's part of its link names
  int lock_fd_ = -1;          // holds `<path>.serving-<tag>.lock` locked while this watcher lives
  mutable std::mutex mutex_;  // one check at a time; guards the fields below
  std::uint64_t links_made_ = 0;
  std::optional<db::SnapshotInfo> loaded_;
  std::optional<FileIdentity> seen_;  // the file last looked at, loaded or refused
  /// The file served was written over in place and did not read as a snapshot: the next one is
  /// taken without comparing keys (there are none left to compare with).
  bool served_damaged_ = false;
  /// Why, while served_damaged_: a copy under a lock of its own, so that /readyz never waits for
  /// a check (a quick_check of the whole file) in progress under mutex_.
  mutable std::mutex damage_mutex_;
  std::optional<std::string> damage_;
  PeriodicThread thread_;  // last: stopped before the members it uses go
};

/// Whether a running replica serves the file at `path` (a SnapshotWatcher holds the lock of its
/// run beside it). Writing to such a file (`pintag import --db` a replica's snapshot) changed that
/// replica's registry alone, with keys the primary does not have, and stuck it there.
bool AReplicaServes(const std::string& path);

}  // namespace pintag::replica
