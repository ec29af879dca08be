#include "app/scan_log_writer.hpp"

#include <algorithm>
#include <exception>
#include <optional>
#include <utility>
#include <vector>

#include "pintag/server/log.hpp"
#include "pintag/server/problem.hpp"

namespace pintag::app {
namespace {

using Clock = std::chrono::steady_clock;

/// Sets `connection`'s busy timeout for one try and puts the one it had back afterwards: a try
/// made while stopping waits no longer than the time left.
class BusyTimeoutFor {
 public:
  BusyTimeoutFor(db::Connection& connection, std::optional<std::chrono::milliseconds> limit)
      : connection_(connection) {
    if (!limit) return;
    before_ = connection.queryInt64("PRAGMA busy_timeout");
    const auto ms = std::clamp<std::int64_t>(limit->count(), 0, *before_);
    connection.execute("PRAGMA busy_timeout = " + std::to_string(ms));
  }
  ~BusyTimeoutFor() {
    if (!before_) return;
    try {
      connection_.execute("PRAGMA busy_timeout = " + std::to_string(*before_));
    } catch (const std::exception&) {
      // The connection goes back to the pool as it is; its next lease waits less, no more.
    }
  }
  BusyTimeoutFor(const BusyTimeoutFor&) = delete;
  BusyTimeoutFor& operator=(const BusyTimeoutFor&) = delete;

 private:
  db::Connection& connection_;
  std::optional<std::int64_t> before_;
};

}  // namespace

ScanLogWriter::ScanLogWriter(std::shared_ptr<ConnectionPool> log,
                             std::shared_ptr<server::Metrics> metrics, std::string failures_counter)
    : log_(std::move(log)),
      metrics_(std::move(metrics)),
      failures_counter_(std::move(failures_counter)),
      thread_([this] { run(); }) {}

ScanLogWriter::~ScanLogWriter() {
  finish();
}

void ScanLogWriter::finish() {
  {
    const std::lock_guard lock(mutex_);
    if (!stopping_) {
      stopping_ = true;
      finish_by_ = Clock::now() + kFinishTimeout;
    }
  }
  queued_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void ScanLogWriter::append(db::ScanRecord scan, const std::string& request_id) {
  const std::size_t bytes = scan.result_json.size();
  std::unique_lock lock(mutex_);
  // Timed under the lock, so that the log's ids (its order) and times agree.
  if (scan.scanned_at.empty()) scan.scanned_at = db::ScanTime(std::chrono::system_clock::now());
  if (stopping_ || queue_.size() >= kMaxBacklogScans || queued_bytes_ + bytes > kMaxBacklogBytes) {
    if (!dropping_ && !stopping_) {
      dropping_ = true;
      server::LogEvent("scan log: " + std::to_string(queue_.size()) +
                           " scans are waiting to be written, the most it holds; later scans are "
                           "answered but not logged until it has room",
                       /*warning=*/true);
    }
    metrics_->increment(failures_counter_);
    server::LogRequestError(request_id, stopping_ ? "scan log: not logged, the server is stopping"
                                                  : "scan log: not logged, the backlog is full");
    return;
  }
  const std::uint64_t sequence = next_sequence_++;
  queue_.push_back({sequence, std::move(scan), request_id});
  queued_bytes_ += bytes;
  held_.store(queue_.size(), std::memory_order_relaxed);
  queued_.notify_one();
  if (behind_) return;
  // Scans waiting side by side time out together: the first says so.
  if (!written_.wait_for(lock, kWaitForWrite, [&] { return done_through_ >= sequence; }) &&
      !behind_) {
    behind_ = true;
    // Said once a spell: from now on an answered scan may not be in the log yet, and a forced
    // stop loses what is held (an operator, or a test killing the server, must know which).
    server::LogEvent("scan log: a scan waited " + std::to_string(kWaitForWrite.count()) +
                         " ms for its row; scans are answered before they are written, held in "
                         "memory, until the log catches up",
                     /*warning=*/true);
  }
}

void ScanLogWriter::run() {
  std::unique_lock lock(mutex_);
  while (true) {
    queued_.wait(lock, [this] { return !queue_.empty() || stopping_; });
    if (queue_.empty()) return;
    if (stopping_ && Clock::now() >= finish_by_) {
      lose(queue_.size(), "not written before the server stopped" +
                              (last_error_.empty() ? "" : " (" + last_error_ + ")"));
      return;
    }
    if (!writeBatch(lock)) {
      // Tried again after a pause, which a stop cuts short (and ends at its deadline).
      const bool was_stopping = stopping_;
      const auto until =
          stopping_ ? std::min(Clock::now() + kRetryPause, finish_by_) : Clock::now() + kRetryPause;
      queued_.wait_until(lock, until, [&] { return stopping_ != was_stopping; });
    }
  }
}

bool ScanLogWriter::writeBatch(std::unique_lock<std::mutex>& lock) {
  std::vector<db::ScanRecord> batch;
  const std::size_t count = std::min(queue_.size(), kMaxBatch);
  batch.reserve(count);
  for (std::size_t i = 0; i < count; ++i) batch.push_back(queue_[i].scan);
  const bool was_failing = !last_error_.empty();
  std::optional<std::chrono::milliseconds> time_left;
  if (stopping_) {
    time_left = std::chrono::duration_cast<std::chrono::milliseconds>(finish_by_ - Clock::now());
  }

  lock.unlock();
  std::optional<db::AppendedScans> appended;
  std::string error;
  // Worth waiting for: a lock held elsewhere, a disk that fills up, a file that cannot be opened
  // now because the process is out of file descriptors, a file moved away (the pool refuses it
  // until it is back). Anything else (a file that is not a database or may not be opened, an
  // I/O error) would fail the same way again: that batch is lost at once.
  bool passing = false;
  try {
    auto connection = log_->acquire();
    const BusyTimeoutFor limit(*connection, time_left);
    auto result = db::AppendScans(*connection, batch);
    if (result) {
      appended = std::move(result).value();
    } else {
      error = result.error().message;
      passing = result.error().code == db::ErrorCode::kBusy ||
                result.error().code == db::ErrorCode::kNoSpace;
    }
  } catch (const server::HttpError& e) {
    // The pool could not lend a connection: it says when that may pass (no descriptor left to
    // open the file with); it refuses a file moved away until it is put back.
    error = e.problem().detail;
    passing = e.problem().retry_after_seconds > 0 || !log_->servesFileAtPath();
  } catch (const std::exception& e) {
    error = e.what();
  }
  lock.lock();

  if (!appended && !passing) {
    for (std::size_t i = 0; i < count; ++i) {
      server::LogRequestError(queue_[i].request_id, "scan log: " + error);
    }
    lose(count, error);
    return true;
  }
  if (!appended) {
    if (error != last_error_) {
      server::LogEvent("scan log: " + std::to_string(queue_.size()) +
                           " scans wait to be written: " + error +
                           "; scans are answered meanwhile and held in memory",
                       /*warning=*/true);
      last_error_ = error;
    }
    return false;
  }
  for (const auto& refusal : appended->refused) {
    metrics_->increment(failures_counter_);
    server::LogRequestError(queue_[refusal.index].request_id, "scan log: " + refusal.error.message);
  }
  dequeue(count);
  if (was_failing && queue_.empty()) {
    server::LogEvent("scan log: caught up, the scans held back are written");
  }
  return true;
}

void ScanLogWriter::lose(std::size_t count, const std::string& why) {
  metrics_->increment(failures_counter_, static_cast<double>(count));
  server::LogEvent("scan log: " + std::to_string(count) + " answered scans are lost: " + why,
                   /*warning=*/true);
  dequeue(count);
}

void ScanLogWriter::dequeue(std::size_t count) {
  for (std::size_t i = 0; i < count && !queue_.empty(); ++i) {
    queued_bytes_ -= queue_.front().scan.result_json.size();
    done_through_ = queue_.front().sequence;
    queue_.pop_front();
  }
  held_.store(queue_.size(), std::memory_order_relaxed);
  if (queue_.empty()) {
    // After a failure writeBatch says it caught up; after a slow write, this does.
    if (behind_ && last_error_.empty()) {
      server::LogEvent("scan log: caught up; answers wait for their rows again");
    }
    last_error_.clear();
    behind_ = false;
  }
  if (dropping_ && queue_.size() < kMaxBacklogScans / 2 && queued_bytes_ < kMaxBacklogBytes / 2) {
    dropping_ = false;
    server::LogEvent("scan log: the backlog has room again");
  }
  written_.notify_all();
}

}  // namespace pintag::app
