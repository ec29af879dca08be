#include "connection_stream.hpp"

#include <netdb.h>
#include <poll.h>
#include <sys/socket.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>

namespace pintag::server {
namespace {

int Milliseconds(std::chrono::microseconds timeout) {
  // Rounded up: a timeout of 500 µs must still wait, not poll once and give up.
  const auto ms = std::chrono::ceil<std::chrono::milliseconds>(timeout).count();
  return static_cast<int>(std::clamp<long long>(ms, 0, 24LL * 3600 * 1000));
}

/// poll() for `events` on `fd`, retried after a signal: > 0 ready, 0 timed out, < 0 failed.
int Wait(int fd, short events, int timeout_ms) {
  pollfd entry{fd, events, 0};
  int ready = 0;
  do {
    ready = ::poll(&entry, 1, timeout_ms);
  } while (ready < 0 && errno == EINTR);
  return ready;
}

/// The peer can still read what is written: the connection is not reset. The end of the stream
/// (a read of 0) is not enough to say it is gone: a client may shut its sending side once its
/// request is sent (`nc -N`, `socat`) and then wait for the answer. cpp-httplib's check took that
/// for a closed connection and wrote such a client nothing.
bool PeerStillThere(int fd) {
  pollfd entry{fd, POLLIN, 0};
  int ready = 0;
  do {
    ready = ::poll(&entry, 1, 0);
  } while (ready < 0 && errno == EINTR);
  if (ready == 0) return true;
  if (ready < 0 || (entry.revents & (POLLERR | POLLHUP | POLLNVAL)) != 0) return false;
  char byte = 0;
  ssize_t n = 0;
  do {
    n = ::recv(fd, &byte, 1, MSG_PEEK | MSG_DONTWAIT);
  } while (n < 0 && errno == EINTR);
  return n >= 0 || errno == EAGAIN || errno == EWOULDBLOCK;
}

void NameAndPort(const sockaddr_storage& address, socklen_t length, std::string& ip, int& port) {
  char host[NI_MAXHOST] = {};
  char service[NI_MAXSERV] = {};
  if (::getnameinfo(reinterpret_cast<const sockaddr*>(&address), length, host, sizeof host, service,
                    sizeof service, NI_NUMERICHOST | NI_NUMERICSERV) == 0) {
    ip = host;
    port = std::atoi(service);
  }
}

}  // namespace

ConnectionStream::ConnectionStream(int fd, std::chrono::microseconds read_timeout,
                                   std::chrono::microseconds write_timeout, std::size_t head_budget,
                                   std::uint64_t min_body_rate)
    : fd_(fd),
      read_timeout_ms_(Milliseconds(read_timeout)),
      write_timeout_ms_(Milliseconds(write_timeout)),
      head_budget_(head_budget),
      min_body_rate_(min_body_rate) {}

int ConnectionStream::bodyWaitMs() const {
  if (min_body_rate_ == 0) return read_timeout_ms_;
  const double allowed_ms =
      kBodyGraceReadTimeouts * static_cast<double>(read_timeout_ms_) +
      1000.0 * static_cast<double>(body_bytes_) / static_cast<double>(min_body_rate_);
  const double waited_ms = std::chrono::duration<double, std::milli>(body_waited_).count();
  const double left_ms = std::ceil(allowed_ms - waited_ms);
  if (left_ms <= 0) return -1;
  return static_cast<int>(std::min<double>(left_ms, read_timeout_ms_));
}

int ConnectionStream::headWaitMs() const {
  const auto deadline = created_ + std::chrono::milliseconds(read_timeout_ms_);
  const double left_ms = std::ceil(
      std::chrono::duration<double, std::milli>(deadline - std::chrono::steady_clock::now())
          .count());
  if (left_ms <= 0) return -1;
  return static_cast<int>(std::min<double>(left_ms, read_timeout_ms_));
}

bool ConnectionStream::is_readable() const {
  return buffered_begin_ < buffered_end_ || Wait(fd_, POLLIN, read_timeout_ms_) > 0;
}

bool ConnectionStream::is_writable() const {
  return Wait(fd_, POLLOUT, write_timeout_ms_) > 0 && PeerStillThere(fd_);
}

ssize_t ConnectionStream::read(char* ptr, size_t size) {
  if (!head_read_) {
    if (head_check_.refusal()) return -1;
    if (handed_out_ >= head_budget_) {
      over_budget_ = true;
      return -1;
    }
    size = std::min(size, head_budget_ - handed_out_);
  } else if (size == 1 && body_line_bytes_ >= kMaxBodyLineBytes) {
    body_line_too_long_ = true;
    return -1;
  }
  if (size == 0) return 0;
  std::size_t n = 0;
  if (buffered_begin_ < buffered_end_) {
    n = std::min(size, buffered_end_ - buffered_begin_);
    std::memcpy(ptr, buffer_.data() + buffered_begin_, n);
    buffered_begin_ += n;
  } else {
    // Bytes already waiting are taken even past the body's pace: a server slow to read them
    // (under load) is not the client's fault.
    // The end is named by the wait chosen here: a read timeout is one whatever the clock says
    // after it.
    const int wait_ms = head_read_ ? bodyWaitMs() : headWaitMs();
    const auto wait_began = std::chrono::steady_clock::now();
    const int ready = Wait(fd_, POLLIN, std::max(wait_ms, 0));
    if (head_read_) {
      // At most the wait asked for: a server stopped while it waited (SIGSTOP, a paused VM) finds
      // the poll ended long after, and that time is not the client's.
      body_waited_ += std::min<std::chrono::steady_clock::duration>(
          std::chrono::steady_clock::now() - wait_began,
          std::chrono::milliseconds(std::max(wait_ms, 0)));
    }
    if (ready <= 0) {
      // A head's wait can end only at its deadline (the first one lasts a whole read timeout,
      // rounded up): too slow, answered 408, whichever wait it was.
      read_end_ =
          !head_read_ || wait_ms < read_timeout_ms_ ? ReadEnd::kTooSlow : ReadEnd::kTimedOut;
      return -1;
    }
    ssize_t got = 0;
    if (head_read_ || head_check_.ended()) {
      // The body: exactly the bytes asked for, which cpp-httplib bounds by the body's length (a
      // chunk-size line it reads one byte at a time).
      do {
        got = ::recv(fd_, ptr, size, 0);
      } while (got < 0 && errno == EINTR);
      if (got <= 0) {
        read_end_ = got == 0 ? ReadEnd::kClosed : ReadEnd::kFailed;
        return got;
      }
      n = static_cast<std::size_t>(got);
    } else {
      // The head, which cpp-httplib reads a byte at a time: one peek, then what it holds of the
      // head is checked and taken into the buffer, never a byte past the head's blank line. A
      // byte past it could be the next request on the connection (pipelined), and the buffer
      // ends with this request.
      do {
        got = ::recv(fd_, buffer_.data(), buffer_.size(), MSG_PEEK);
      } while (got < 0 && errno == EINTR);
      if (got <= 0) {
        read_end_ = got == 0 ? ReadEnd::kClosed : ReadEnd::kFailed;
        return got;
      }
      const std::size_t take =
          headBytesToTake(std::string_view(buffer_.data(), static_cast<std::size_t>(got)));
      do {
        got = ::recv(fd_, buffer_.data(), take, 0);
      } while (got < 0 && errno == EINTR);
      if (got <= 0 || head_check_.refusal()) return -1;
      n = std::min(size, static_cast<std::size_t>(got));
      std::memcpy(ptr, buffer_.data(), n);
      buffered_begin_ = n;
      buffered_end_ = static_cast<std::size_t>(got);
    }
  }
  if (head_read_ && chunked_ && !chunked_->take(std::string_view(ptr, n))) return -1;
  if (!head_read_) {
    handed_out_ += n;
    return static_cast<ssize_t>(n);
  }
  body_bytes_ += n;
  if (size == 1 && *ptr != '\n') {
    ++body_line_bytes_;  // a line being read byte by byte; a larger read is content, not a line
  } else {
    body_line_bytes_ = 0;
  }
  return static_cast<ssize_t>(n);
}

std::size_t ConnectionStream::headBytesToTake(std::string_view peeked) {
  // Checked as they are taken, a byte at a time: the check says where the head ends (its blank
  // line) and where it breaks a rule, and no byte past either is taken.
  for (std::size_t i = 0; i < peeked.size(); ++i) {
    if (!head_check_.take(peeked.substr(i, 1)) || head_check_.ended()) return i + 1;
  }
  return peeked.size();
}

ssize_t ConnectionStream::write(const char* ptr, size_t size) {
  if (!is_writable()) {
    write_failed_ = true;
    return -1;
  }
  ssize_t sent = 0;
  do {
    sent = ::send(fd_, ptr, size, MSG_NOSIGNAL);
  } while (sent < 0 && errno == EINTR);
  if (sent < 0) write_failed_ = true;
  return sent;
}

void ConnectionStream::get_remote_ip_and_port(std::string& ip, int& port) const {
  sockaddr_storage address{};
  socklen_t length = sizeof address;
  if (::getpeername(fd_, reinterpret_cast<sockaddr*>(&address), &length) == 0) {
    NameAndPort(address, length, ip, port);
  }
}

void ConnectionStream::get_local_ip_and_port(std::string& ip, int& port) const {
  sockaddr_storage address{};
  socklen_t length = sizeof address;
  if (::getsockname(fd_, reinterpret_cast<sockaddr*>(&address), &length) == 0) {
    NameAndPort(address, length, ip, port);
  }
}

}  // namespace pintag::server
