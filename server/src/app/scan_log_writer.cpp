#include "app/scan_log_writer.hpp"

#include <exception>
#include <optional>
#include <utility>
#include <vector>

#include "pintag/server/log.hpp"
#include "pintag/server/problem.hpp"

namespace pintag::app {

using Clock = std::chrono::steady_clock;

ScanLogWriter::ScanLogWriter(std::shared_ptr<ConnectionPool> log,
                             std::shared_ptr<server::Metrics> metrics, std::string failures_counter)
    : log_(std::move(log)),
      metrics_(std::move(metrics)),
      failures_counter_(std::move(failures_counter)),
      thread_([this] { run(); }) {}

ScanLogWriter::~ScanLogWriter() {
  {
    const std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  queued_.notify_all();
  thread_.join();
}

void ScanLogWriter::append(db::ScanRecord scan, const std::string& request_id) {
  if (scan.scanned_at.empty()) scan.scanned_at = db::ScanTime(std::chrono::system_clock::now());
  const std::size_t bytes = scan.result_json.size();
  std::unique_lock lock(mutex_);
  if (queue_.size() >= kMaxBacklogScans || queued_bytes_ + bytes > kMaxBacklogBytes) {
    if (!dropping_) {
      dropping_ = true;
      server::LogEvent("scan log: " + std::to_string(queue_.size()) +
                           " scans are waiting to be written, the most it holds; later scans are "
                           "answered but not logged until it has room",
                       /*warning=*/true);
    }
    metrics_->increment(failures_counter_);
    server::LogRequestError(request_id, "scan log: not logged, the backlog is full");
    return;
  }
  const std::uint64_t sequence = next_sequence_++;
  queue_.push_back({sequence, std::move(scan), request_id});
  queued_bytes_ += bytes;
  queued_.notify_one();
  if (behind_) return;
  if (!written_.wait_for(lock, kWaitForWrite, [&] { return done_through_ >= sequence; })) {
    behind_ = true;
  }
}

std::size_t ScanLogWriter::backlog() const {
  const std::lock_guard lock(mutex_);
  return queue_.size();
}

void ScanLogWriter::run() {
  std::unique_lock lock(mutex_);
  std::optional<Clock::time_point> finish_by;
  while (true) {
    queued_.wait(lock, [this] { return !queue_.empty() || stopping_; });
    if (queue_.empty()) return;
    if (stopping_ && !finish_by) finish_by = Clock::now() + kFinishTimeout;
    if (finish_by && Clock::now() >= *finish_by) {
      lose(queue_.size(), "not written before the server stopped" +
                              (last_error_.empty() ? "" : " (" + last_error_ + ")"));
      return;
    }
    // A failed write is tried again after a pause; one that was busy has waited already.
    if (!writeBatch(lock)) written_.wait_for(lock, std::chrono::seconds(1));
  }
}

bool ScanLogWriter::writeBatch(std::unique_lock<std::mutex>& lock) {
  std::vector<db::ScanRecord> batch;
  const std::size_t count = std::min(queue_.size(), kMaxBatch);
  batch.reserve(count);
  for (std::size_t i = 0; i < count; ++i) batch.push_back(queue_[i].scan);
  const bool was_failing = !last_error_.empty();

  lock.unlock();
  std::optional<db::AppendedScans> appended;
  std::string error;
  // Worth waiting for: a lock held elsewhere, a disk that fills up, a database file moved away
  // (the pool refuses it until it is back). Anything else (a file that is not a database, an I/O
  // error) would fail the same way again: that batch is lost at once, as before the writer.
  bool passing = false;
  try {
    auto connection = log_->acquire();
    auto result = db::AppendScans(*connection, batch);
    if (result) {
      appended = std::move(*result);
    } else {
      error = result.error().message;
      passing = result.error().code == db::ErrorCode::kBusy ||
                result.error().code == db::ErrorCode::kNoSpace;
    }
  } catch (const server::HttpError& e) {
    // The pool refuses a file that is not at its path any more until it is put back; one it
    // cannot open (not a database) stays so.
    error = e.problem().detail;
    passing = !log_->servesFileAtPath();
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
  for (std::size_t i = 0; i < count; ++i) {
    queued_bytes_ -= queue_.front().scan.result_json.size();
    done_through_ = queue_.front().sequence;
    queue_.pop_front();
  }
  if (was_failing && queue_.empty()) {
    server::LogEvent("scan log: caught up, the scans held back are written");
  }
  if (queue_.empty()) {
    last_error_.clear();
    behind_ = false;
  }
  if (dropping_ && queue_.size() < kMaxBacklogScans / 2 && queued_bytes_ < kMaxBacklogBytes / 2) {
    dropping_ = false;
    server::LogEvent("scan log: the backlog has room again");
  }
  written_.notify_all();
  return true;
}

void ScanLogWriter::lose(std::size_t count, const std::string& why) {
  metrics_->increment(failures_counter_, static_cast<double>(count));
  server::LogEvent("scan log: " + std::to_string(count) + " answered scans are lost: " + why,
                   /*warning=*/true);
  for (std::size_t i = 0; i < count && !queue_.empty(); ++i) {
    queued_bytes_ -= queue_.front().scan.result_json.size();
    done_through_ = queue_.front().sequence;
    queue_.pop_front();
  }
  if (queue_.empty()) behind_ = false;
  written_.notify_all();
}

}  // namespace pintag::app
