#include "app/connection_pool.hpp"

#include <sys/stat.h>

#include "pintag/server/log.hpp"
#include "pintag/server/problem.hpp"

namespace pintag::app {

namespace {

constexpr const char* kMovedDetail =
    "the database file was moved, deleted or replaced while the server ran; put it back, or "
    "restart the server to serve the file now at its path";

}  // namespace

ConnectionPool::ConnectionPool(std::string path, int busy_timeout_ms, bool read_only)
    : path_(std::move(path)), busy_timeout_ms_(busy_timeout_ms), read_only_(read_only) {
  struct stat status {};
  if (!read_only_ && ::stat(path_.c_str(), &status) == 0) {
    identified_ = true;
    device_ = status.st_dev;
    inode_ = status.st_ino;
  }
}

ConnectionPool::~ConnectionPool() {
  if (moved_ && !log_emptied_) emptyLogOfMovedFile();
}

bool ConnectionPool::servesFileAtPath() {
  if (read_only_ || !identified_) return true;
  struct stat status {};
  const bool here =
      ::stat(path_.c_str(), &status) == 0 && status.st_dev == device_ && status.st_ino == inode_;
  bool left = false;
  bool back = false;
  {
    const std::lock_guard lock(mutex_);
    left = !here && !moved_;
    back = here && moved_;
    moved_ = !here;
    if (back) log_emptied_ = false;
  }
  if (left) {
    server::LogEvent(path_ +
                         " is no longer the database this server opened (moved, deleted or "
                         "replaced); requests that need the database are refused until it is "
                         "back or the server restarts",
                     /*warning=*/true);
    emptyLogOfMovedFile();
  } else if (back) {
    server::LogEvent(path_ + " is the database this server opened again");
  }
  return here;
}

// The log's frames go into the file the connections have open (wherever it is now, or unlinked),
// and the log at the path is truncated, so it is nobody's. Needs an idle connection and no reader
// in the log; when there is none now, the destructor tries again at shutdown.
void ConnectionPool::emptyLogOfMovedFile() {
  std::unique_ptr<db::Connection> connection;
  {
    const std::lock_guard lock(mutex_);
    if (log_emptied_ || idle_.empty()) return;
    connection = std::move(idle_.back());
    idle_.pop_back();
  }
  bool emptied = false;
  try {
    db::Statement checkpoint = connection->prepare("PRAGMA wal_checkpoint(TRUNCATE)");
    // One row: busy (1 when readers kept it from finishing), log frames, frames checkpointed.
    emptied = checkpoint.step() && checkpoint.getInt64(0) == 0;
  } catch (const std::exception& e) {
    server::LogEvent(std::string("checkpointing the moved database's log failed: ") + e.what(),
                     /*warning=*/true);
  }
  if (!emptied) {
    const std::lock_guard lock(mutex_);
    idle_.push_back(std::move(connection));  // for the next try
    return;
  }
  {
    const std::lock_guard lock(mutex_);
    log_emptied_ = true;
    ++generation_;  // leases out now are closed when they come back
    idle_.clear();
  }
  server::LogEvent("the writes in " + path_ +
                   "-wal were moved into the file this server opened, and the log emptied");
}

ConnectionPool::Lease::~Lease() {
  if (!connection_ || pool_ == nullptr) return;
  const std::lock_guard lock(pool_->mutex_);
  if (generation_ == pool_->generation_) pool_->idle_.push_back(std::move(connection_));
}

void ConnectionPool::renew(const std::string& path) {
  std::vector<std::unique_ptr<db::Connection>> closing;
  {
    const std::lock_guard lock(mutex_);
    ++generation_;
    path_ = path;
    closing.swap(idle_);
  }
}

ConnectionPool::Lease ConnectionPool::acquire() {
  if (!servesFileAtPath()) throw server::HttpError(503, kMovedDetail, "Database File Replaced");
  while (true) {
    std::uint64_t generation = 0;
    std::string path;
    {
      const std::lock_guard lock(mutex_);
      generation = generation_;
      path = path_;
      if (!idle_.empty()) {
        std::unique_ptr<db::Connection> connection = std::move(idle_.back());
        idle_.pop_back();
        return Lease(this, std::move(connection), generation);
      }
    }
    // Opened outside the lock (an open may wait on the database). A replica's snapshot can be
    // swapped meanwhile and the file just read from path_ removed (SnapshotWatcher::check), so an
    // open that fails after a renew() is tried again on the new file.
    try {
      db::ConnectionOptions options;
      options.create = false;
      options.read_only = read_only_;
      options.busy_timeout_ms = busy_timeout_ms_;
      return Lease(this, std::make_unique<db::Connection>(path, options), generation);
    } catch (const std::exception& e) {
      {
        const std::lock_guard lock(mutex_);
        if (generation_ != generation) continue;
      }
      server::LogEvent("cannot open database " + path + ": " + e.what(), /*warning=*/true);
      throw server::HttpError(503, "the database is not reachable", "Service Unavailable");
    }
  }
}

}  // namespace pintag::app
