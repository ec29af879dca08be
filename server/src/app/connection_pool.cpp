#include "app/connection_pool.hpp"

#include <iostream>

#include "pintag/server/problem.hpp"

namespace pintag::app {

ConnectionPool::ConnectionPool(std::string path, int busy_timeout_ms)
    : path_(std::move(path)), busy_timeout_ms_(busy_timeout_ms) {}

ConnectionPool::Lease::~Lease() {
  if (!connection_ || pool_ == nullptr) return;
  const std::lock_guard lock(pool_->mutex_);
  pool_->idle_.push_back(std::move(connection_));
}

ConnectionPool::Lease ConnectionPool::acquire() {
  {
    const std::lock_guard lock(mutex_);
    if (!idle_.empty()) {
      std::unique_ptr<db::Connection> connection = std::move(idle_.back());
      idle_.pop_back();
      return Lease(this, std::move(connection));
    }
  }
  try {
    db::ConnectionOptions options;
    options.create = false;
    options.busy_timeout_ms = busy_timeout_ms_;
    return Lease(this, std::make_unique<db::Connection>(path_, options));
  } catch (const std::exception& e) {
    std::cerr << "pintag serve: cannot open database " << path_ << ": " << e.what() << "\n";
    throw server::HttpError(503, "the database is not reachable", "Service Unavailable");
  }
}

}  // namespace pintag::app
