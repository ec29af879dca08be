#pragma once
// Database connections for the worker threads. A db::Connection is used by one thread at a time
// (it is opened NOMUTEX), so each request leases one from this pool and gives it back when done;
// connections are opened on demand and kept (at most one per concurrent request). renew() makes
// later leases open the file now at the path (a replica's new snapshot) while leases in flight
// finish on the file they opened.

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "pintag/db/sqlite.hpp"

namespace pintag::app {

class ConnectionPool {
 public:
  /// `path` must be an existing database (the serve command opened and migrated it first).
  explicit ConnectionPool(std::string path, int busy_timeout_ms = 5000, bool read_only = false);

  /// A connection for the calling thread until the lease ends.
  class Lease {
   public:
    Lease(ConnectionPool* pool, std::unique_ptr<db::Connection> connection,
          std::uint64_t generation)
        : pool_(pool), connection_(std::move(connection)), generation_(generation) {}
    Lease(Lease&&) noexcept = default;
    Lease& operator=(Lease&&) = delete;
    Lease(const Lease&) = delete;
    Lease& operator=(const Lease&) = delete;
    ~Lease();
    db::Connection& operator*() const { return *connection_; }
    db::Connection* operator->() const { return connection_.get(); }

   private:
    ConnectionPool* pool_;
    std::unique_ptr<db::Connection> connection_;
    std::uint64_t generation_;
  };

  /// Throws server::HttpError 503 when the database cannot be opened (an open that failed
  /// because renew() changed the file meanwhile is tried again on the new one).
  Lease acquire();

  /// Closes the idle connections; later leases open `path` (a replica's newly loaded snapshot),
  /// and connections leased before are closed when they come back.
  void renew(const std::string& path);

 private:
  std::string path_;
  int busy_timeout_ms_;
  bool read_only_;
  std::mutex mutex_;
  std::uint64_t generation_ = 0;
  std::vector<std::unique_ptr<db::Connection>> idle_;
};

}  // namespace pintag::app
