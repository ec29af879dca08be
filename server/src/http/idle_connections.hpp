#pragma once
// Connections waiting for their next request (their first, or the next on a kept-alive
// connection), parked in one epoll set on one thread instead of each holding a worker, until the
// request's whole head has arrived. Waiting in a worker, N connections that sent nothing (a
// browser's preconnects, a port scan, an attack) held N workers for the keep-alive timeout each,
// and every other client waited behind them: 16 idle sockets delayed /livez by 20 s on a 4-worker
// server. A head sent a byte at a time is waited for here too, so it holds no worker either.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <thread>

namespace pintag::server {

/// Bytes of a head after which a worker takes it even unended: far above a real request's head
/// (a few hundred bytes to a few KiB), well within any receive queue.
inline constexpr std::size_t kWorkerTakesHeadBytes = std::size_t{32} * 1024;

/// What drain() drops after refusing a head: a client whose head was refused sends little
/// after it, and one that keeps sending is not a client to spend the waiting thread on.
inline constexpr std::size_t kDrainAfterRefusedHead = std::size_t{1} << 20;

/// What has arrived of a connection's next request, read without taking it from the socket.
enum class HeadState {
  kNothing,  ///< no byte yet
  kPart,     ///< part of a head
  kReady,    ///< a worker should take it: the whole head (up to its blank line), or
             ///< kWorkerTakesHeadBytes of it (the worker reads the rest within the budget), or the
             ///< peer stopped sending, or the socket failed
};
/// Empty lines before a request are taken from the socket first (RFC 9112, 2.2, asks a server
/// to ignore them).
HeadState PeekRequestHead(int fd, std::size_t head_budget);

class IdleConnections {
 public:
  using Clock = std::chrono::steady_clock;
  /// Called on the waiting thread with a connection that has bytes to read, or that its peer
  /// closed: the callee owns `fd` again (hands it to a worker, or closes it).
  using Ready = std::function<void(int fd, std::size_t requests_left)>;

  struct Limits {
    /// Connections waiting at once; parking one more closes the one whose wait ends first, so a
    /// flood of idle sockets cannot keep new clients out.
    std::size_t max_parked = 1024;
    std::size_t head_budget = 0;  ///< as PeekRequestHead's
    /// A head whose first bytes came must be whole this long after them, else
    /// `answer_head_timeout` writes its answer (without waiting) and the connection is closed.
    /// One that sent nothing is closed without a word when its wait ends.
    std::chrono::milliseconds head_timeout{5000};
    std::function<void(int fd)> answer_head_timeout;
    /// How long drain() waits for bytes to drop: as nginx's lingering close.
    std::chrono::milliseconds drain_quiet{5000};
    std::chrono::milliseconds drain_time{30000};
  };

  IdleConnections(Ready ready, Limits limits);
  ~IdleConnections();  ///< closeAll(), then joins the thread
  IdleConnections(const IdleConnections&) = delete;
  IdleConnections& operator=(const IdleConnections&) = delete;

  /// Waits for `fd`'s next request until `deadline`, then shuts and closes it; once the request's
  /// first bytes come, its head has Limits::head_timeout from then instead, and is answered with
  /// Limits::answer_head_timeout when it runs out. After closeAll() it closes `fd` at once.
  void park(int fd, std::size_t requests_left, Clock::time_point deadline);
  /// Takes a connection whose answer has been written and whose client may still be sending
  /// what the server will not read (a body it refused before reading, a head it refused): its
  /// sending side is shut, what comes is read and dropped here, and it is closed when the client
  /// closes, when nothing came for Limits::drain_quiet, at Limits::drain_time after this call,
  /// or after `max_bytes`. Closed with unread bytes, the connection would be reset, and a reset
  /// can reach the client before it has read the answer: a client sending a refused 6 MB photo
  /// (one that reads only once it has sent all) saw a broken pipe instead of its 401.
  void drain(int fd, std::size_t max_bytes);
  /// Closes every parked connection and each one parked from now on (the server is stopping).
  void closeAll();
  /// Connections waiting now.
  std::size_t parked() const;

 private:
  struct Waiting {
    std::size_t requests_left = 0;
    Clock::time_point deadline;
    bool head_began = false;           ///< its deadline is then the head's
    bool draining = false;             ///< drain(): read and dropped, never handed to a worker
    Clock::time_point drain_end;       ///< drain(): Limits::drain_time after it began
    std::size_t drain_bytes_left = 0;  ///< drain(): bytes still to drop before closing
  };
  /// Reads and drops what has come on a draining connection, at most kDropPerTurn a call so
  /// that one fast sender does not keep this thread from the others (a draining connection is
  /// watched level-triggered: what is left is reported again). False when it is to be closed
  /// (the client closed, the socket failed, or the byte limit was reached). mutex_ held.
  bool dropWhatCame(int fd, Waiting& waiting);
  /// Watches `fd` for `events` as `waiting`, closing the one whose wait ends first when full.
  void add(int fd, const Waiting& waiting, std::uint32_t events);
  void run();
  /// Takes `fd` out of the set and closes it without a word; mutex_ held.
  void closeLocked(int fd);
  /// Answers a head that ran out of time (Limits::answer_head_timeout), then drains the
  /// connection (drain()); no lock held.
  void answerTimeoutAndClose(int fd);

  Ready ready_;
  Limits limits_;
  int epoll_fd_ = -1;
  int wake_fd_ = -1;  ///< an eventfd that ends the thread's wait (closeAll, destruction)
  mutable std::mutex mutex_;
  std::map<int, Waiting> waiting_;
  bool closed_ = false;
  bool ending_ = false;
  std::thread thread_;
};

}  // namespace pintag::server
