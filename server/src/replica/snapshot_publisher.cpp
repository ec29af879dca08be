#include "replica/snapshot_publisher.hpp"

#include <fstream>
#include <iomanip>
#include <iostream>
#include <random>
#include <sstream>

#include "pintag/db/database.hpp"

namespace pintag::replica {

namespace {

std::string RandomEpoch() {
  std::random_device random;
  std::ostringstream hex;
  hex << std::hex << std::setfill('0') << std::setw(8) << random() << std::setw(8) << random();
  return hex.str();
}

}  // namespace

SnapshotPublisher::SnapshotPublisher(std::string live_path, std::string out_path)
    : live_path_(std::move(live_path)), out_path_(std::move(out_path)), epoch_(RandomEpoch()) {}

db::Result<std::int64_t> SnapshotPublisher::liveVersion() {
  const std::lock_guard lock(version_mutex_);
  try {
    if (!version_connection_) {
      version_connection_.emplace(live_path_, db::ConnectionOptions{.create = false});
    }
  } catch (const db::SqliteError& e) {
    return db::Error{db::ErrorCode::kStorage, e.what()};
  }
  return db::RegistryVersion(*version_connection_);
}

std::optional<SnapshotPublisher::ReaderSlot> SnapshotPublisher::tryReader() {
  if (++readers_ > kMaxSnapshotReaders) {
    --readers_;
    return std::nullopt;
  }
  return std::optional<ReaderSlot>(std::in_place, &readers_);
}

db::Result<db::SnapshotInfo> SnapshotPublisher::publishLocked() {
  try {
    if (!live_) live_.emplace(live_path_, db::ConnectionOptions{.create = false});
  } catch (const db::SqliteError& e) {
    return db::Error{db::ErrorCode::kStorage, e.what()};
  }
  const db::Result<std::int64_t> version = db::RegistryVersion(*live_);
  if (!version) return version.error();
  if (published_ && published_->registry_version == *version) return *published_;
  db::Result<db::SnapshotInfo> written = db::WriteSnapshot(*live_, out_path_);
  if (!written) return written.error();
  published_ = *written;
  std::cerr << "pintag serve: published snapshot " << out_path_ << " (registry version "
            << written->registry_version << ", " << written->bytes << " bytes)\n";
  return *written;
}

db::Result<db::SnapshotInfo> SnapshotPublisher::publish() {
  const std::lock_guard lock(mutex_);
  return publishLocked();
}

db::Result<PublishedSnapshot> SnapshotPublisher::read() {
  const std::lock_guard lock(mutex_);
  db::Result<db::SnapshotInfo> info = publishLocked();
  if (!info) return info.error();
  // Read under the lock: the file is not replaced meanwhile, so bytes and version agree.
  std::ifstream in(out_path_, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  if (!in) return db::Error{db::ErrorCode::kStorage, "cannot read the snapshot " + out_path_};
  return PublishedSnapshot{*info, std::move(bytes).str()};
}

void SnapshotPublisher::start(std::chrono::milliseconds interval) {
  thread_.start(interval, [this, last_error = std::string()]() mutable {
    const db::Result<db::SnapshotInfo> published = publish();
    if (!published && published.error().message != last_error) {
      std::cerr << "pintag serve: cannot publish a snapshot: " << published.error().message << "\n";
    }
    last_error = published ? "" : published.error().message;
  });
}

}  // namespace pintag::replica
