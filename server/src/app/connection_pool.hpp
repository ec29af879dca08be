#pragma once
// Database connections for the worker threads. A db::Connection is used by one thread at a time
// (it is opened NOMUTEX), so each request leases one from this pool and gives it back when done;
// connections are opened on demand and kept (at most one per concurrent request). renew() makes
// later leases open the file now at the path (a replica's new snapshot) while leases in flight
// finish on the file they opened.
//
// A writable pool serves the file that was at its path when it was made. When that file is moved,
// deleted or replaced while the server runs, SQLite's connections keep the old file but its
// write-ahead log stays at the path, where a database put there later would take it as its own
// (a restored backup undone, or corrupted). So while another file or none is at the path the
// pool refuses every lease (503), and at every request, readiness probe and at shutdown it tries
// to move what the log holds into the file it belongs to (a checkpoint) and to empty the log.
// Put back, the file is served again.

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "pintag/db/sqlite.hpp"
#include "pintag/server/log_throttle.hpp"

namespace pintag::app {

class ConnectionPool {
 public:
  /// `path` must be an existing database (the serve command opened and migrated it first).
  explicit ConnectionPool(std::string path, int busy_timeout_ms = 5000, bool read_only = false);
  /// Looks at the path once more and, when the served file has left it, checkpoints its log
  /// (closing does not: SQLite leaves the log of a moved database as it is).
  ~ConnectionPool();
  ConnectionPool(const ConnectionPool&) = delete;
  ConnectionPool& operator=(const ConnectionPool&) = delete;

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
  /// because renew() changed the file meanwhile is tried again on the new one), or when a
  /// writable pool's file is no longer at its path.
  Lease acquire();

  /// For a writable pool: whether the file it serves is still the one at its path (always true
  /// for a read-only pool, whose file is replaced by design). While it is away, each call tries
  /// to checkpoint the log into it and empty the log, without waiting on readers. One stat when
  /// the file is there; the readiness check and a forced stop call it too, so a moved file is
  /// found within a probe interval even when no request comes.
  bool servesFileAtPath();

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
  // The served file's device and inode (writable pools); `moved_` while it is not at the path.
  bool identified_ = false;
  std::uint64_t device_ = 0;
  std::uint64_t inode_ = 0;
  bool moved_ = false;
  bool told_log_kept_ = false;  ///< a try to empty the log failed and was logged, this departure
  /// Every request fails the same way while the file cannot be opened: one warning in 10 s.
  server::LogThrottle open_failures_;

  void emptyLogOfMovedFile();
};

}  // namespace pintag::app
