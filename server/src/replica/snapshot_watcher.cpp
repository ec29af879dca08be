#include "replica/snapshot_watcher.hpp"

#include <sys/stat.h>

#include <iostream>

namespace pintag::replica {

SnapshotWatcher::SnapshotWatcher(std::string path, db::SnapshotInfo loaded, OnLoaded on_loaded)
    : path_(std::move(path)),
      on_loaded_(std::move(on_loaded)),
      loaded_(std::move(loaded)),
      seen_(Stat(path_)) {}

SnapshotWatcher::~SnapshotWatcher() {
  {
    const std::lock_guard lock(stop_mutex_);
    stopping_ = true;
  }
  stop_changed_.notify_all();
  if (thread_.joinable()) thread_.join();
}

std::optional<SnapshotWatcher::Identity> SnapshotWatcher::Stat(const std::string& path) {
  struct stat status {};
  if (::stat(path.c_str(), &status) != 0) return std::nullopt;
  return Identity{status.st_dev, status.st_ino, status.st_size,
                  std::int64_t{status.st_mtim.tv_sec} * 1'000'000'000 + status.st_mtim.tv_nsec};
}

bool SnapshotWatcher::check() {
  const std::lock_guard lock(mutex_);
  const std::optional<Identity> now = Stat(path_);
  if (!now || now == seen_) return false;  // gone (keep serving) or unchanged
  seen_ = now;
  const db::Result<db::SnapshotInfo> verified = db::VerifySnapshot(path_);
  if (!verified) {
    std::cerr << "pintag serve: ignoring the new file at " << path_ << ": "
              << verified.error().message << "; still serving registry version "
              << loaded_.registry_version << "\n";
    return false;
  }
  loaded_ = *verified;
  on_loaded_(loaded_);
  std::cerr << "pintag serve: loaded snapshot " << path_ << " (registry version "
            << loaded_.registry_version << ")\n";
  return true;
}

void SnapshotWatcher::start(std::chrono::milliseconds interval) {
  thread_ = std::thread([this, interval] {
    while (true) {
      check();
      std::unique_lock lock(stop_mutex_);
      if (stop_changed_.wait_for(lock, interval, [this] { return stopping_; })) return;
    }
  });
}

db::SnapshotInfo SnapshotWatcher::loaded() const {
  const std::lock_guard lock(mutex_);
  return loaded_;
}

}  // namespace pintag::replica
