#pragma once
// Writes the scan log from a thread of its own, so that a scan never waits on the log's lock on a
// worker thread. Another process writing the database (`pintag import`) holds that lock for as
// long as it writes; appended on the worker, each scan waited out SQLite's busy timeout (5 s),
// and a few scans took every worker, stalling lookups, labels and probes with them.
//
// A scan is timed when it is handed over, then written in order with the scans queued beside it,
// in one transaction. While the log keeps up, append() returns once its scan is written, so an
// answered scan is in the log as before. When a scan has waited kWaitForWrite for its row (the
// lock is held elsewhere, or a write is that slow), append() returns at once until the backlog
// is written: the scans are held in memory, up to kMaxBacklogScans and kMaxBacklogBytes of JSON;
// past that a scan is dropped and counted. Only what may pass is waited for (a lock, a full disk,
// no file descriptor left to open the file with, a file moved away); a log
// that cannot be written otherwise (not a database, an I/O error) loses its scans at once,
// counted.
// finish() writes the backlog for at most kFinishTimeout from when it is called, each try cut to
// the time left; what is left then is lost and counted. A forced stop (the process ends without
// finish()) loses what is held: backlog() says how much, for the stop to log.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>

#include "app/connection_pool.hpp"
#include "pintag/db/scan_log.hpp"
#include "pintag/server/metrics.hpp"

namespace pintag::app {

class ScanLogWriter {
 public:
  static constexpr std::chrono::milliseconds kWaitForWrite{1000};
  static constexpr std::size_t kMaxBacklogScans = 100'000;
  static constexpr std::size_t kMaxBacklogBytes = 64 << 20;
  static constexpr std::size_t kMaxBatch = 500;  ///< scans written in one transaction
  static constexpr std::chrono::seconds kFinishTimeout{10};

  static constexpr std::chrono::milliseconds kRetryPause{1000};

  /// Writes to `log`'s file. Scans it loses are added to `failures_counter` in `metrics`.
  ScanLogWriter(std::shared_ptr<ConnectionPool> log, std::shared_ptr<server::Metrics> metrics,
                std::string failures_counter);
  /// finish(), when it has not run.
  ~ScanLogWriter();
  ScanLogWriter(const ScanLogWriter&) = delete;
  ScanLogWriter& operator=(const ScanLogWriter&) = delete;

  /// Times `scan` now (when it has no time) and queues it; returns once it is written, or at
  /// once while the log is behind. `request_id` names the request in the server log.
  void append(db::ScanRecord scan, const std::string& request_id);

  /// Scans queued and not yet written. Read without waiting on the writer, so a stop that
  /// cannot wait may still log what it abandons.
  std::size_t backlog() const { return held_.load(std::memory_order_relaxed); }

  /// Writes the backlog (for at most kFinishTimeout) and ends the thread; later appends are
  /// counted as lost. Call once serving has ended.
  void finish();

 private:
  struct Queued {
    std::uint64_t sequence = 0;
    db::ScanRecord scan;
    std::string request_id;
  };
  void run();
  /// Writes the queue's first scans once; false when the log could not be written for a reason
  /// that may pass (they are tried again). Scans that cannot be written at all are lost.
  bool writeBatch(std::unique_lock<std::mutex>& lock);
  /// Counts, logs and drops the queue's first `count` scans.
  void lose(std::size_t count, const std::string& why);
  /// Takes the queue's first `count` scans off it as done, and what follows from the queue
  /// then: waiters woken, the behind and backlog-full states left when it has room.
  void dequeue(std::size_t count);

  std::shared_ptr<ConnectionPool> log_;
  std::shared_ptr<server::Metrics> metrics_;
  std::string failures_counter_;

  mutable std::mutex mutex_;
  std::condition_variable queued_;   ///< a scan was queued, or the writer is stopping
  std::condition_variable written_;  ///< done_through_ moved on
  std::deque<Queued> queue_;
  std::size_t queued_bytes_ = 0;
  std::uint64_t next_sequence_ = 1;
  std::uint64_t done_through_ = 0;  ///< every scan up to this one is written or lost
  bool behind_ = false;             ///< a scan waited kWaitForWrite; cleared when caught up
  bool dropping_ = false;           ///< the backlog is full; logged once until it has room
  bool stopping_ = false;
  std::chrono::steady_clock::time_point finish_by_;  ///< when stopping_: the deadline
  std::string last_error_;  ///< why the last write failed; empty once the backlog is written
  std::atomic<std::size_t> held_{0};  ///< queue_.size(), for backlog()
  std::thread thread_;                ///< last: started once everything above is made
};

}  // namespace pintag::app
