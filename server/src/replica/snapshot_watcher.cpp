#include "replica/snapshot_watcher.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <stdexcept>

namespace pintag::replica {

SnapshotWatcher::SnapshotWatcher(std::string path, OnLoaded on_loaded)
    : path_(std::move(path)), on_loaded_(std::move(on_loaded)) {
  // Serving links of an earlier run: their files are no longer open by anyone.
  const std::filesystem::path target(path_);
  const std::string prefix = target.filename().string() + ".serving-";
  const std::filesystem::path directory =
      target.parent_path().empty() ? std::filesystem::path(".") : target.parent_path();
  std::error_code ignored;
  for (const auto& entry : std::filesystem::directory_iterator(directory, ignored)) {
    if (entry.path().filename().string().rfind(prefix, 0) == 0)
      std::filesystem::remove(entry.path(), ignored);
  }
  const std::lock_guard lock(mutex_);
  seen_ = Stat(path_);
  const db::Result<db::SnapshotInfo> loaded = linkAndVerify();
  if (!loaded) throw std::runtime_error(loaded.error().message);
  loaded_ = *loaded;
}

std::optional<SnapshotWatcher::Identity> SnapshotWatcher::Stat(const std::string& path) {
  struct stat status {};
  if (::stat(path.c_str(), &status) != 0) return std::nullopt;
  return Identity{status.st_dev, status.st_ino, status.st_size,
                  std::int64_t{status.st_mtim.tv_sec} * 1'000'000'000 + status.st_mtim.tv_nsec};
}

db::Result<db::SnapshotInfo> SnapshotWatcher::linkAndVerify() {
  const std::string link = path_ + ".serving-" + std::to_string(++links_made_);
  ::unlink(link.c_str());
  if (::link(path_.c_str(), link.c_str()) != 0) {
    return db::Error{db::ErrorCode::kStorage,
                     "cannot link " + path_ + " to " + link + ": " + std::strerror(errno)};
  }
  db::Result<db::SnapshotInfo> verified = db::VerifySnapshot(link);
  if (!verified) ::unlink(link.c_str());
  return verified;
}

bool SnapshotWatcher::check() {
  const std::lock_guard lock(mutex_);
  const std::optional<Identity> now = Stat(path_);
  if (!now || now == seen_) return false;  // gone (keep serving) or unchanged
  seen_ = now;
  const db::Result<db::SnapshotInfo> verified = linkAndVerify();
  if (!verified) {
    std::cerr << "pintag serve: ignoring the new file at " << path_ << ": "
              << verified.error().message << "; still serving registry version "
              << loaded_->registry_version << "\n";
    return false;
  }
  const std::string previous = loaded_->path;
  loaded_ = *verified;
  on_loaded_(*loaded_);
  ::unlink(previous.c_str());  // connections still reading it keep it until they close
  std::cerr << "pintag serve: loaded snapshot " << path_ << " (registry version "
            << loaded_->registry_version << ")\n";
  return true;
}

void SnapshotWatcher::start(std::chrono::milliseconds interval) {
  thread_.start(interval, [this] { check(); });
}

db::SnapshotInfo SnapshotWatcher::loaded() const {
  const std::lock_guard lock(mutex_);
  return *loaded_;
}

}  // namespace pintag::replica
