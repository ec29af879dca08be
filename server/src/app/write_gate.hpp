#pragma once
// At most a set number of requests may write the database at once; the others are answered 503
// with Retry-After at once. A writer waits for SQLite's write lock (up to the busy timeout,
// 5 s) on its worker thread. While another process holds that lock (`pintag import` on the
// served file), writers queued behind it took every worker thread, and lookups, labels, scans
// and the liveness probe waited with them (GET /livez stalled 4.6 s). So the gate lets writers
// have half the threads, and the rest of the server keeps answering.

#include <mutex>

namespace pintag::app {

class WriteGate {
 public:
  /// `capacity` writers at once (at least 1).
  explicit WriteGate(int capacity);

  /// Held by one writing request until it ends.
  class Permit {
   public:
    explicit Permit(WriteGate* gate) : gate_(gate) {}
    Permit(Permit&& other) noexcept : gate_(other.gate_) { other.gate_ = nullptr; }
    Permit& operator=(Permit&&) = delete;
    Permit(const Permit&) = delete;
    Permit& operator=(const Permit&) = delete;
    ~Permit();

   private:
    WriteGate* gate_;
  };

  /// A permit, or server::HttpError 503 (Retry-After: 1) when `capacity` writers are in.
  Permit enter();

  int capacity() const { return capacity_; }

 private:
  const int capacity_;
  std::mutex mutex_;
  int writers_ = 0;
};

/// Half the worker threads, at least one: the writers a server of `threads` admits at once.
int WriteGateCapacity(int threads);

}  // namespace pintag::app
