#pragma once
// One request's view of a client connection, as cpp-httplib 0.11.4 reads and writes it: the
// library's own socket stream, with one thing added. cpp-httplib bounds each header line but
// stores every line until the blank one, so a client that never ends its headers grew the
// worker's memory as fast as it sent (measured: 158 MiB sent in 12 s, the server's resident
// memory 127 → 712 MB, from one connection and no token). This stream hands out at most
// `head_budget` bytes until the request's head has been read (`headRead`), then fails the read,
// which ends the request; `overBudget` then says why, so the server can answer 431 and close.
// In the body it bounds the one thing cpp-httplib reads there without bound: a line read byte
// by byte (a chunked body's chunk-size line or its last line) may be at most `kMaxBodyLineBytes`
// long, then the read fails and `bodyLineTooLong` says why (measured before: 60 MiB of one
// chunk-size line took a server from 200 to 262 MB resident).
//
// And it checks the head's syntax as it hands it out (RequestHeadCheck): a head that breaks a
// rule fails the read that brought the offending byte, and `headRefusal` says why. A chunked
// body's framing is checked the same way (ChunkedBodyCheck, once `expectChunkedBody` is called),
// and `chunkedRefusal` says why.
//
// And it bounds how slowly a body may come (`min_body_rate`): cpp-httplib's read timeout applies
// to each read, so a client sending a byte every few seconds kept its worker for as long as its
// declared length lasted. The time this stream spends waiting for the body's bytes may be at
// most kBodyGraceReadTimeouts read timeouts plus a second for each `min_body_rate` bytes that
// came; a read that would wait past that fails, and `readEnd` is kTooSlow (as Apache's
// mod_reqtimeout `body=20,MinRate=500`; 0 bounds nothing). Only waiting is counted, each wait
// at most as long as it was asked to be: a server that stops reading (busy, or stopped and
// continued) holds the client back by flow control, and that time is not the client's.
//
// And it bounds how long a worker reads a head: one read timeout from when the stream was made,
// whatever the pace. A head over kWorkerTakesHeadBytes is handed to a worker unfinished
// (IdleConnections waits for smaller ones without one), and with a read timeout for each read, a
// client adding a header byte every few seconds held the worker for as long as the head budget
// lasted (a review: 72 s for 36 KiB, days for 96 KiB; four such connections stopped a server).
// A read that would wait past it fails, and `headTooSlow` says so (answered 408).
//
// Otherwise it behaves as cpp-httplib's: a read or write waits at most its timeout; the head is
// read through a 4 KiB buffer (cpp-httplib reads it one byte at a time); a write first checks
// that the peer can still read. The buffer lives as long as the stream, one request, so no read
// takes a byte past the request's own: the next request on the connection (pipelined) stays in
// the socket. cpp-httplib's stream filled its buffer whole, and with it lost that request.

#include <httplib.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "chunked_body_check.hpp"
#include "request_head_check.hpp"

namespace pintag::server {

class ConnectionStream final : public httplib::Stream {
 public:
  /// Far above a chunk-size line with extensions; cpp-httplib reads such lines one byte a call.
  static constexpr std::size_t kMaxBodyLineBytes = std::size_t{8} * 1024;
  /// The wait a body may take before its pace counts, in read timeouts (20 s by default).
  static constexpr int kBodyGraceReadTimeouts = 4;

  ConnectionStream(int fd, std::chrono::microseconds read_timeout,
                   std::chrono::microseconds write_timeout, std::size_t head_budget,
                   std::uint64_t min_body_rate = 0);

  bool is_readable() const override;
  bool is_writable() const override;
  ssize_t read(char* ptr, size_t size) override;
  ssize_t write(const char* ptr, size_t size) override;
  void get_remote_ip_and_port(std::string& ip, int& port) const override;
  void get_local_ip_and_port(std::string& ip, int& port) const override;
  socket_t socket() const override { return fd_; }

  /// The request line and headers are in: the body, if any, is not counted against the head's
  /// budget.
  void headRead() { head_read_ = true; }
  /// True once a read was refused because the head ran past `head_budget`.
  bool overBudget() const { return over_budget_; }
  /// True once a read of the head failed because it was not whole a read timeout after the
  /// stream was made.
  bool headTooSlow() const { return !head_read_ && read_end_ == ReadEnd::kTooSlow; }
  /// Set once a read was refused because the head broke a rule of its syntax.
  const std::optional<RequestHeadCheck::Refusal>& headRefusal() const {
    return head_check_.refusal();
  }
  /// True once a read was refused because a line of the body ran past kMaxBodyLineBytes.
  bool bodyLineTooLong() const { return body_line_too_long_; }
  /// The body is chunked: its framing is checked from here on (ChunkedBodyCheck).
  void expectChunkedBody() { chunked_.emplace(); }
  /// Why a read was refused because the chunked body's framing broke; nothing when it was not.
  std::optional<std::string> chunkedRefusal() const {
    return chunked_ ? chunked_->refusal() : std::nullopt;
  }

  /// Why the last read that failed on the socket failed: no byte within the read timeout, the
  /// peer closed its sending side, the socket failed, or the body came slower than
  /// `min_body_rate` (kNone: none did).
  enum class ReadEnd { kNone, kTimedOut, kClosed, kFailed, kTooSlow };
  ReadEnd readEnd() const { return read_end_; }
  /// Bytes of the body read so far, and how long this stream waited for them.
  std::uint64_t bodyBytes() const { return body_bytes_; }
  std::chrono::steady_clock::duration bodyWaited() const { return body_waited_; }

  /// The answer leaves up to `bytes` of the body unread, which the client may still send: the
  /// connection is drained of that much before it is closed (IdleConnections::drain).
  void leavesUnread(std::size_t bytes) { unread_ = std::max(unread_, bytes); }
  std::size_t unread() const { return unread_; }

  /// An answer was written (the logger saw it), and whether it asked to close the connection.
  void answered(bool close) {
    answered_ = true;
    close_ = close_ || close;
  }
  bool wasAnswered() const { return answered_; }
  bool closeAfterAnswer() const { return close_; }
  /// True once a write failed or timed out: the answer did not all reach the client (it closed
  /// the connection, or stopped reading for the write timeout).
  bool writeFailed() const { return write_failed_; }
  /// When the stream was made: the moment the request's head was there to be read (or had run
  /// past the budget). A request's time is counted from here.
  std::chrono::steady_clock::time_point created() const { return created_; }

 private:
  /// How many of `peeked`, the bytes waiting in the socket, a read of the head takes, checking
  /// them: all, or through the blank line that ends the head, or the byte the check refused.
  std::size_t headBytesToTake(std::string_view peeked);
  /// How long a read of the body may wait for its next byte: the read timeout, or less when the
  /// body's pace would fall under `min_body_rate` sooner; negative once it has (see above).
  int bodyWaitMs() const;
  /// How long a read of the head may wait: what is left of one read timeout since `created_`;
  /// negative once it has run out.
  int headWaitMs() const;

  int fd_;
  int read_timeout_ms_;
  int write_timeout_ms_;
  std::size_t head_budget_;
  std::uint64_t min_body_rate_;
  std::size_t handed_out_ = 0;  ///< bytes read() has returned while the head was being read
  bool head_read_ = false;
  bool over_budget_ = false;
  RequestHeadCheck head_check_;      ///< fed the head's bytes as they are taken from the socket
  std::size_t body_line_bytes_ = 0;  ///< bytes of the body's current line read one at a time
  bool body_line_too_long_ = false;
  std::optional<ChunkedBodyCheck> chunked_;  ///< fed a chunked body's bytes as they are read
  std::chrono::steady_clock::duration body_waited_{};  ///< in poll() for the body's bytes
  std::uint64_t body_bytes_ = 0;
  ReadEnd read_end_ = ReadEnd::kNone;
  std::size_t unread_ = 0;
  bool answered_ = false;
  bool close_ = false;
  bool write_failed_ = false;
  std::array<char, 4096> buffer_{};
  std::size_t buffered_begin_ = 0;
  std::size_t buffered_end_ = 0;
  std::chrono::steady_clock::time_point created_ = std::chrono::steady_clock::now();
};

}  // namespace pintag::server
