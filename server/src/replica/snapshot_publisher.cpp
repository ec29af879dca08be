#include "replica/snapshot_publisher.hpp"

#include <algorithm>
#include <fstream>
#include <iomanip>
#include <random>
#include <sstream>

#include "pintag/db/database.hpp"
#include "pintag/server/log.hpp"

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
  if (failure_ && Clock::now() < retry_at_) return *failure_;
  db::Result<db::SnapshotInfo> written = writeIfChanged();
  if (!written) return failed(written.error());
  if (failure_) {
    failure_.reset();
    failures_in_a_row_ = 0;
    failing_since_.reset();
    updateStatus();
  }
  return written;
}

db::Result<db::SnapshotInfo> SnapshotPublisher::writeIfChanged() {
  try {
    if (!live_) live_.emplace(live_path_, db::ConnectionOptions{.create = false});
  } catch (const db::SqliteError& e) {
    return db::Error{db::ErrorCode::kStorage, e.what()};
  }
  const db::Result<std::int64_t> version = db::RegistryVersion(*live_);
  if (!version) return version.error();
  const bool ours = publishedFileIsOurs();
  if (published_ && published_->registry_version == *version && ours) return *published_;
  if (published_ && !ours && !failure_) {
    server::LogEvent("the published snapshot " + out_path_ +
                         " was removed or changed by another process; publishing it again",
                     /*warning=*/true);
  }
  db::Result<db::SnapshotInfo> written = db::WriteSnapshot(*live_, out_path_);
  if (!written) return written.error();
  published_ = *written;
  published_file_ = IdentifyFile(out_path_);
  updateStatus();
  server::LogEvent("published snapshot " + out_path_ + " (registry version " +
                   std::to_string(written->registry_version) + ", " +
                   std::to_string(written->bytes) + " bytes)");
  return *written;
}

db::Error SnapshotPublisher::failed(db::Error error) {
  // 1, 2, 4, … s, at most kMaxRetryDelay.
  const std::chrono::seconds delay =
      std::min(kMaxRetryDelay, kFirstRetryDelay * (1 << std::min(failures_in_a_row_, 6)));
  ++failures_in_a_row_;
  retry_at_ = Clock::now() + delay;
  if (!failing_since_) failing_since_ = std::chrono::system_clock::now();
  // The count goes to the log only: a replica quotes the error it is answered, and one that
  // changed at every try was logged by every replica at every try.
  failure_ = error;
  server::LogEvent("cannot publish a snapshot to " + out_path_ + ": " + error.message + " (" +
                       std::to_string(failures_in_a_row_) + " in a row; next try in " +
                       std::to_string(delay.count()) + " s)",
                   /*warning=*/true);
  updateStatus();
  return error;
}

bool SnapshotPublisher::publishedFileIsOurs() const {
  return published_file_ && IdentifyFile(out_path_) == published_file_;
}

SnapshotPublisher::Status SnapshotPublisher::status() const {
  const std::lock_guard lock(status_mutex_);
  return status_;
}

void SnapshotPublisher::updateStatus() {
  Status status;
  // The version replicas are given: none while the file is not the one written (removed,
  // replaced, or a publication failed after it went).
  if (published_ && publishedFileIsOurs()) status.published_version = published_->registry_version;
  if (failure_) status.error = failure_->message;
  status.failing_since = failing_since_;
  const std::lock_guard lock(status_mutex_);
  status_ = std::move(status);
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
  // Each failed try is logged where it is made (publishLocked), at most once a retry delay.
  thread_.start(interval, [this] { (void)publish(); });
}

}  // namespace pintag::replica
