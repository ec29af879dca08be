#pragma once
// The signals `pintag serve` answers: SIGINT and SIGTERM stop it gracefully, SIGHUP makes a
// replica reload. One waiter thread takes them in turn, however the process's other threads mask
// them.
//
// Blocking the signals in every thread and taking them with sigwait is not enough: a library can
// start threads before main() runs (OpenBLAS, the system BLAS wherever a package pulled it
// in, starts its workers when it is loaded), those threads do not block the signals, and the
// kernel may hand a process-directed SIGTERM to one of them, whose default action then ends the
// process with its requests in flight. So each signal has a handler, wherever it runs, that only
// writes the signal's number to a pipe; the waiter reads the pipe. The server's own threads still
// block the signals, so that their system calls are not interrupted.

#include <chrono>
#include <csignal>

namespace pintag::cli {

/// One per process (the handlers write to one pipe).
class ServeSignals {
 public:
  /// Handles SIGHUP from now on (a reload the waiter takes when it starts) and blocks it in the
  /// calling thread. SIGINT and SIGTERM end the process at once, as their default action would
  /// (a server still starting, e.g. a follower waiting for its first snapshot, just ends), also
  /// where it is PID 1 in a container and the default action would be ignored.
  ServeSignals();
  ServeSignals(const ServeSignals&) = delete;
  ServeSignals& operator=(const ServeSignals&) = delete;

  /// From now on SIGINT and SIGTERM ask for a graceful stop; blocked in the calling thread, so
  /// that the threads it starts afterwards inherit the block.
  void takeStopSignals();

  /// Waits for the next signal and returns it (SIGHUP, SIGINT or SIGTERM), or 0 after wake() (or
  /// should the pipe fail).
  /// Only the waiter thread calls it: it lets the signals through to that thread.
  int wait();
  /// As wait(), but gives up after `timeout`: then -1.
  int waitFor(std::chrono::milliseconds timeout);

  /// Makes wait() return 0.
  void wake();
};

}  // namespace pintag::cli
