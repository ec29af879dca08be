#pragma once
// Raw TCP to a server on 127.0.0.1, for tests that must send what an HTTP client library would
// not (half requests, chunked bodies past a limit, requests hidden in a body).

#include <functional>
#include <string>

namespace pintag::test {

/// A connected socket to 127.0.0.1:`port`, or -1 when it cannot connect. The caller closes it.
int ConnectLoopback(int port);

/// Sends all of `bytes` on `fd` (no SIGPIPE when the peer has gone). False when it could not.
bool SendAll(int fd, const std::string& bytes);

/// What arrives on `fd` until the peer closes it, nothing arrives for `quiet_s` seconds, or
/// `done(received so far)` holds after a read.
std::string ReceiveUntil(int fd, int quiet_s,
                         const std::function<bool(const std::string&)>& done = nullptr);

/// True once `received` holds a whole HTTP response: its headers, and as many body bytes as its
/// Content-Length says (none without one). A `done` for ReceiveUntil on a kept-alive connection.
bool HasWholeResponse(const std::string& received);

/// Connects, sends `request`, returns ReceiveUntil(…, quiet_s, done) and closes; "" when it
/// cannot connect.
std::string SendRaw(int port, const std::string& request, int quiet_s,
                    const std::function<bool(const std::string&)>& done = nullptr);

}  // namespace pintag::test
