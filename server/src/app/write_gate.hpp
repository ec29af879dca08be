#pragma once
// At most half the worker threads may be in requests that write the database. A writer waits for
// SQLite's write lock (up to the busy timeout, 5 s) on its worker thread. While another process
// holds that lock (`pintag import` on the served file), writers queued behind it took every worker
// thread, and lookups, labels, scans and the liveness probe waited with them (GET /livez stalled
// 4.6 s). A writer that finds the gate full waits for a permit, since writes take milliseconds
// when nothing else holds the lock (six admins saving a plan at once all get in); but once the
// writers inside have held their permits for kStuck, the lock is someone else's and a writer is
// answered 503 with Retry-After instead of waiting with them.

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <vector>

namespace pintag::app {

class WriteGate {
 public:
  using Clock = std::chrono::steady_clock;

  /// `capacity` writers at once (at least 1).
  explicit WriteGate(int capacity);

  /// Held by one writing request until it ends.
  class Permit {
   public:
    Permit(WriteGate* gate, Clock::time_point entered) : gate_(gate), entered_(entered) {}
    Permit(Permit&& other) noexcept : gate_(other.gate_), entered_(other.entered_) {
      other.gate_ = nullptr;
    }
    Permit& operator=(Permit&&) = delete;
    Permit(const Permit&) = delete;
    Permit& operator=(const Permit&) = delete;
    ~Permit();

   private:
    WriteGate* gate_;
    Clock::time_point entered_;
  };

  /// How long writers may all stay in before those waiting for a permit are refused.
  static constexpr std::chrono::milliseconds kStuck{1000};

  /// A permit, or server::HttpError 503 (Retry-After: 1) when `capacity` writers are in and the
  /// one that entered first has been in for kStuck.
  Permit enter();

 private:
  const int capacity_;
  std::mutex mutex_;
  std::condition_variable left_;
  std::vector<Clock::time_point> entered_;  ///< of the writers in
};

/// Half the worker threads, at least one: the writers a server of `threads` admits at once.
int WriteGateCapacity(int threads);

}  // namespace pintag::app
