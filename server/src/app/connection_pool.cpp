#include "app/connection_pool.hpp"

#include <sys/stat.h>

#include <filesystem>

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
  // Shutdown may come before any request or probe saw the file leave: look once more.
  servesFileAtPath();
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
    if (left) told_log_kept_ = false;
  }
  if (left) {
    server::LogEvent(path_ +
                         " is no longer the database this server opened (moved, deleted or "
                         "replaced); requests that need the database are refused until it is "
                         "back or the server restarts",
                     /*warning=*/true);
  } else if (back) {
    server::LogEvent(path_ + " is the database this server opened again");
  }
  // Tried on every look while the file is away, not once: a reader or a lease still out can keep
  // the first try from emptying the log, and a write committed by a lease taken before the move
  // refills it.
  if (!here) emptyLogOfMovedFile();
  return here;
}

// The log's frames go into the file the connections have open (wherever it is now, or unlinked),
// and the log at the path is truncated, so it is nobody's. Uses an idle connection without
// waiting on readers (a refused request must not wait); a try that cannot finish now leaves the
// connection idle for the next, and says so once.
void ConnectionPool::emptyLogOfMovedFile() {
  std::unique_ptr<db::Connection> connection;
  {
    const std::lock_guard lock(mutex_);
    if (idle_.empty()) return;
    connection = std::move(idle_.back());
    idle_.pop_back();
  }
  bool emptied = false;
  // What the log held: a truncating checkpoint reports its frames as 0 once it is done.
  std::error_code no_size;
  const std::uintmax_t log_bytes = std::filesystem::file_size(path_ + "-wal", no_size);
  std::string why = "readers held it";
  try {
    connection->execute("PRAGMA busy_timeout = 0");
    {
      db::Statement checkpoint = connection->prepare("PRAGMA wal_checkpoint(TRUNCATE)");
      // One row: busy (1 when readers kept it from finishing), log frames, frames checkpointed.
      emptied = checkpoint.step() && checkpoint.getInt64(0) == 0;
    }
    connection->execute("PRAGMA busy_timeout = " + std::to_string(busy_timeout_ms_));
  } catch (const std::exception& e) {
    emptied = false;
    why = e.what();
  }
  if (!emptied) {
    bool tell = false;
    {
      const std::lock_guard lock(mutex_);
      idle_.push_back(std::move(connection));  // for the next try
      tell = !told_log_kept_;
      told_log_kept_ = true;
    }
    if (tell) {
      server::LogEvent("the log " + path_ +
                           "-wal of the moved database could not be emptied yet (" + why +
                           "); trying again at each request, probe and at shutdown",
                       /*warning=*/true);
    }
    return;
  }
  {
    const std::lock_guard lock(mutex_);
    ++generation_;  // leases out now come back to idle_ (moved) or are closed (back)
    idle_.clear();
  }
  if (!no_size && log_bytes > 0) {
    server::LogEvent("the writes in " + path_ +
                     "-wal were moved into the file this server opened, and the log emptied");
  }
}

ConnectionPool::Lease::~Lease() {
  if (!connection_ || pool_ == nullptr) return;
  // A transaction left open (its COMMIT and ROLLBACK failed) would refuse the next request's
  // BEGIN, or hold its reads to an old state: such a connection is closed, not kept.
  if (connection_->inTransaction()) {
    try {
      connection_->execute("ROLLBACK");
    } catch (...) {
      // Closed below when still in the transaction.
    }
    if (connection_->inTransaction()) {
      connection_.reset();
      return;
    }
  }
  bool moved = false;
  {
    const std::lock_guard lock(pool_->mutex_);
    moved = pool_->moved_;
    // While the served file is away, a connection that may just have written to its log is kept
    // for emptying it: closing does not checkpoint a moved file.
    if (generation_ == pool_->generation_ || moved) pool_->idle_.push_back(std::move(connection_));
  }
  if (moved) pool_->emptyLogOfMovedFile();
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
      auto connection = std::make_unique<db::Connection>(path, options);
      if (auto line = open_failures_.settle("database " + path + " opens again")) {
        server::LogEvent(*line);
      }
      return Lease(this, std::move(connection), generation);
    } catch (const std::exception& e) {
      {
        const std::lock_guard lock(mutex_);
        if (generation_ != generation) continue;
      }
      if (auto line = open_failures_.admit("cannot open database " + path + ": " + e.what())) {
        server::LogEvent(*line, /*warning=*/true);
      }
      // A process out of file descriptors opens the file on a later try, so the client is told
      // when to ask again; a file it may not open, or one that is no database, stays so.
      const auto* sqlite = dynamic_cast<const db::SqliteError*>(&e);
      const bool may_pass = sqlite != nullptr && sqlite->outOfDescriptors();
      throw server::HttpError(server::Problem{503, "Service Unavailable",
                                              "the database is not reachable", "about:blank",
                                              may_pass ? 1 : 0});
    }
  }
}

}  // namespace pintag::app
