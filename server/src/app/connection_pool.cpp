#include "app/connection_pool.hpp"

#include <iostream>

#include "pintag/server/problem.hpp"

namespace pintag::app {

ConnectionPool::ConnectionPool(std::string path, int busy_timeout_ms, bool read_only)
    : path_(std::move(path)), busy_timeout_ms_(busy_timeout_ms), read_only_(read_only) {}

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
      std::cerr << "pintag serve: cannot open database " << path << ": " << e.what() << "\n";
      throw server::HttpError(503, "the database is not reachable", "Service Unavailable");
    }
  }
}

}  // namespace pintag::app
