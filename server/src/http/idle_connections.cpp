#include "idle_connections.hpp"

#include <poll.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdint>
#include <stdexcept>
#include <string_view>
#include <vector>

namespace pintag::server {
namespace {

void ShutAndClose(int fd) {
  ::shutdown(fd, SHUT_RDWR);
  ::close(fd);
}

/// Takes the empty lines a client may send before a request (RFC 9112, 2.2: a stray CRLF after a
/// body): cpp-httplib would answer such a line 400, and the client would take that for the
/// answer to its next request. At most kMaxEmptyLineBytes, in one read: a client that sends
/// nothing but empty lines kept this loop (on a worker, or on the waiting thread under its lock)
/// taking them as fast as they came, and the server stalled; past that many, its next "request
/// line" is empty, answered 400, and the connection closed.
void DropEmptyLinesBeforeARequest(int fd) {
  constexpr std::size_t kMaxEmptyLineBytes = 64;
  std::array<char, kMaxEmptyLineBytes> peeked{};
  ssize_t n = 0;
  do {
    n = ::recv(fd, peeked.data(), peeked.size(), MSG_PEEK | MSG_DONTWAIT);
  } while (n < 0 && errno == EINTR);
  if (n <= 0) return;
  std::size_t empty = 0;
  while (empty < static_cast<std::size_t>(n) && (peeked[empty] == '\r' || peeked[empty] == '\n')) {
    ++empty;
  }
  if (empty == 0) return;
  do {
    n = ::recv(fd, peeked.data(), empty, MSG_DONTWAIT);
  } while (n < 0 && errno == EINTR);
}

}  // namespace

HeadState PeekRequestHead(int fd, std::size_t head_budget) {
  DropEmptyLinesBeforeARequest(fd);
  thread_local std::vector<char> peeked;
  const std::size_t enough = std::min(head_budget, kWorkerTakesHeadBytes);
  peeked.resize(enough);
  ssize_t n = 0;
  do {
    n = ::recv(fd, peeked.data(), peeked.size(), MSG_PEEK | MSG_DONTWAIT);
  } while (n < 0 && errno == EINTR);
  if (n < 0)
    return errno == EAGAIN || errno == EWOULDBLOCK ? HeadState::kNothing : HeadState::kReady;
  // Past kWorkerTakesHeadBytes a worker reads the rest (and refuses a head past the budget with
  // 431): a queue that never holds the whole budget (a small receive window) would otherwise keep
  // such a head waiting, and each peek of a head sent in small pieces copies all of it again.
  if (n == 0 || static_cast<std::size_t>(n) >= enough) {
    return HeadState::kReady;
  }
  const std::string_view head(peeked.data(), static_cast<std::size_t>(n));
  // cpp-httplib takes a bare LF as a line's end too.
  const bool whole = head.find("\r\n\r\n") != std::string_view::npos ||
                     head.find("\n\n") != std::string_view::npos ||
                     head.find("\n\r\n") != std::string_view::npos;
  if (whole) return HeadState::kReady;
  // A peer that stopped sending halfway goes to a worker, which reads to the end and closes: the
  // rest of its head will never come.
  pollfd peer{fd, POLLRDHUP, 0};
  if (::poll(&peer, 1, 0) > 0 && (peer.revents & (POLLRDHUP | POLLHUP | POLLERR)) != 0) {
    return HeadState::kReady;
  }
  return HeadState::kPart;
}

IdleConnections::IdleConnections(Ready ready, Limits limits)
    : ready_(std::move(ready)), limits_(std::move(limits)) {
  limits_.max_parked = std::max<std::size_t>(1, limits_.max_parked);
  epoll_fd_ = ::epoll_create1(EPOLL_CLOEXEC);
  wake_fd_ = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  if (epoll_fd_ < 0 || wake_fd_ < 0) throw std::runtime_error("cannot create an epoll set");
  epoll_event wake{};
  wake.events = EPOLLIN;
  wake.data.fd = wake_fd_;
  ::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, wake_fd_, &wake);
  thread_ = std::thread([this] { run(); });
}

IdleConnections::~IdleConnections() {
  {
    const std::lock_guard lock(mutex_);
    ending_ = true;
  }
  closeAll();
  thread_.join();
  ::close(wake_fd_);
  ::close(epoll_fd_);
}

void IdleConnections::park(int fd, std::size_t requests_left, Clock::time_point deadline) {
  Waiting waiting;
  waiting.requests_left = requests_left;
  waiting.deadline = deadline;
  // Edge-triggered: part of a head that stays unread is reported again only when more comes.
  add(fd, waiting, EPOLLIN | EPOLLRDHUP | EPOLLET);
}

void IdleConnections::drain(int fd, std::size_t max_bytes) {
  ::shutdown(fd, SHUT_WR);
  const Clock::time_point now = Clock::now();
  Waiting waiting;
  waiting.deadline = now + limits_.drain_quiet;
  waiting.draining = true;
  waiting.drain_end = now + limits_.drain_time;
  waiting.drain_bytes_left = max_bytes;
  add(fd, waiting, EPOLLIN | EPOLLRDHUP);  // level-triggered: see dropWhatCame
}

void IdleConnections::add(int fd, const Waiting& waiting, std::uint32_t events) {
  const std::lock_guard lock(mutex_);
  if (closed_) {
    ShutAndClose(fd);
    return;
  }
  if (waiting_.size() >= limits_.max_parked) {
    const auto first_to_end = std::min_element(
        waiting_.begin(), waiting_.end(),
        [](const auto& a, const auto& b) { return a.second.deadline < b.second.deadline; });
    closeLocked(first_to_end->first);
  }
  epoll_event event{};
  event.events = events;
  event.data.fd = fd;
  if (::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, fd, &event) != 0) {
    ShutAndClose(fd);
    return;
  }
  waiting_[fd] = waiting;
  const std::uint64_t one = 1;  // the thread's wait may end later than this deadline
  [[maybe_unused]] const ssize_t written = ::write(wake_fd_, &one, sizeof one);
}

bool IdleConnections::dropWhatCame(int fd, Waiting& waiting) {
  // One recv a connection a turn: with 64 connections reported at once that is 1 MiB, a few
  // milliseconds under the lock that workers parking connections wait on (256 KiB a connection
  // held it for 57 ms a turn under 200 refused uploads).
  constexpr std::size_t kDropPerTurn = 16384;
  std::array<char, 16384> sink{};
  bool came = false;
  for (std::size_t dropped = 0; dropped < kDropPerTurn;) {
    const std::size_t want = std::min(sink.size(), waiting.drain_bytes_left);
    if (want == 0) return false;
    const ssize_t n = ::recv(fd, sink.data(), want, MSG_DONTWAIT);
    if (n > 0) {
      waiting.drain_bytes_left -= static_cast<std::size_t>(n);
      dropped += static_cast<std::size_t>(n);
      came = true;
      continue;
    }
    if (n == 0) return false;  // the client closed: nothing more to wait for
    if (errno == EINTR) continue;
    if (errno != EAGAIN && errno != EWOULDBLOCK) return false;
    break;
  }
  if (came) {
    waiting.deadline = std::min(Clock::now() + limits_.drain_quiet, waiting.drain_end);
  }
  return true;
}

void IdleConnections::closeAll() {
  const std::lock_guard lock(mutex_);
  closed_ = true;
  while (!waiting_.empty()) closeLocked(waiting_.begin()->first);
  const std::uint64_t one = 1;
  [[maybe_unused]] const ssize_t written = ::write(wake_fd_, &one, sizeof one);
}

std::size_t IdleConnections::parked() const {
  const std::lock_guard lock(mutex_);
  return waiting_.size();
}

void IdleConnections::closeLocked(int fd) {
  ::epoll_ctl(epoll_fd_, EPOLL_CTL_DEL, fd, nullptr);
  waiting_.erase(fd);
  ShutAndClose(fd);
}

void IdleConnections::answerTimeoutAndClose(int fd) {
  if (!limits_.answer_head_timeout) {
    ShutAndClose(fd);
    return;
  }
  limits_.answer_head_timeout(fd);
  drain(fd, kDrainAfterRefusedHead);  // so that closing does not reset it under the answer
}

void IdleConnections::run() {
  std::array<epoll_event, 64> events{};
  std::vector<std::pair<int, std::size_t>> ready;
  std::vector<int> timed_out;  ///< heads begun and not ended in time: answered 408
  for (;;) {
    int timeout_ms = 1000;
    {
      const std::lock_guard lock(mutex_);
      if (ending_) return;
      const Clock::time_point now = Clock::now();
      for (const auto& [fd, waiting] : waiting_) {
        const auto left =
            std::chrono::ceil<std::chrono::milliseconds>(waiting.deadline - now).count();
        timeout_ms = static_cast<int>(std::clamp<std::int64_t>(left, 0, timeout_ms));
      }
    }
    const int n =
        ::epoll_wait(epoll_fd_, events.data(), static_cast<int>(events.size()), timeout_ms);
    if (n < 0 && errno != EINTR) return;
    ready.clear();
    timed_out.clear();
    {
      const std::lock_guard lock(mutex_);
      for (int i = 0; i < n; ++i) {
        const int fd = events[static_cast<std::size_t>(i)].data.fd;
        if (fd == wake_fd_) {
          std::uint64_t count = 0;
          [[maybe_unused]] const ssize_t got = ::read(wake_fd_, &count, sizeof count);
          continue;
        }
        const auto it = waiting_.find(fd);
        if (it == waiting_.end()) continue;  // closed meanwhile
        if (it->second.draining) {
          if (!dropWhatCame(fd, it->second)) closeLocked(fd);
          continue;
        }
        const HeadState head = PeekRequestHead(fd, limits_.head_budget);
        if (head != HeadState::kReady) {
          if (head == HeadState::kPart && !it->second.head_began) {
            // The keep-alive wait ends with the first byte; the head has its own time from it.
            it->second.head_began = true;
            it->second.deadline = Clock::now() + limits_.head_timeout;
          }
          continue;
        }
        ::epoll_ctl(epoll_fd_, EPOLL_CTL_DEL, fd, nullptr);
        ready.emplace_back(fd, it->second.requests_left);
        waiting_.erase(it);
      }
      const Clock::time_point now = Clock::now();
      for (auto it = waiting_.begin(); it != waiting_.end();) {
        if (it->second.deadline > now) {
          ++it;
          continue;
        }
        const int fd = it->first;
        const bool head_began = it->second.head_began && !it->second.draining;
        ++it;
        if (head_began) {
          ::epoll_ctl(epoll_fd_, EPOLL_CTL_DEL, fd, nullptr);
          waiting_.erase(fd);
          timed_out.push_back(fd);
        } else {
          closeLocked(fd);
        }
      }
    }
    // Outside the lock: answering logs, and workers parking connections wait on the lock.
    for (const int fd : timed_out) answerTimeoutAndClose(fd);
    for (const auto& [fd, left] : ready) ready_(fd, left);
  }
}

}  // namespace pintag::server
