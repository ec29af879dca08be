// The bytes a client sends on one TCP connection, through the server as `pintag serve` runs it:
// a real HttpServer on a loopback port, so the connection loop, the request-head budget and its
// syntax checks (folded headers, a bad Content-Length, smuggling), chunk-line limits, keep-alive
// and pipelining run, which http_request's one-request path (answerRaw) skips. The client sends
// the input (tokens put in as for http_request), stops sending, and reads until the server
// closes. The server must close within kCloseWithin (a hang is a finding), and every answer read
// must be a well-formed response that is not a 500, each error problem+json as http_request
// checks. Each input starts from the same registry (ResetRegistry).

#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <string_view>

#include "fuzz_support.hpp"
#include "pintag/server/http_server.hpp"
#include "pintag/server/log.hpp"

namespace {

/// Longer than any answer takes under ASan (a label render, about 2 s), shorter than libFuzzer's
/// -timeout so that a connection left open is named as such.
constexpr std::chrono::seconds kCloseWithin{20};

pintag::server::HttpServer& Server() {
  static const auto server = [] {
    pintag::server::ServerOptions options;
    options.port = 0;
    options.threads = 2;
    auto made = std::make_unique<pintag::server::HttpServer>(pintag::fuzz::Registry().api, options);
    std::string error;
    if (!made->start(&error)) {
      std::fprintf(stderr, "cannot start the server: %s\n", error.c_str());
      std::abort();
    }
    return made;
  }();
  return *server;
}

/// Sends `request` (as much as the server takes before it closes), stops sending, and returns
/// everything the server wrote until it closed.
std::string Exchange(const std::string& request) {
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(Server().port()));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  // A long run makes hundreds of connections a second, and each leaves its local port in
  // TIME_WAIT for a minute: at 384 a second one used up the ephemeral range and connect() failed
  // (2026-12-07). A port is waited for, a while, rather than taken as a finding.
  int sock = -1;
  for (int attempt = 0; sock < 0; ++attempt) {
    sock = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (sock < 0) std::abort();
    if (::connect(sock, reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0) break;
    const int error = errno;
    ::close(sock);
    sock = -1;
    if ((error != EADDRNOTAVAIL && error != EAGAIN && error != EINTR) || attempt == 200) {
      std::fprintf(stderr, "cannot connect to the server: %s\n", std::strerror(error));
      std::abort();
    }
    ::usleep(50'000);
  }
  // Loopback buffers hold far more than -max_len; a server that refuses early and closes makes
  // the rest of the write fail, which is its right.
  std::size_t sent = 0;
  while (sent < request.size()) {
    const ssize_t n = ::send(sock, request.data() + sent, request.size() - sent, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    sent += static_cast<std::size_t>(n);
  }
  ::shutdown(sock, SHUT_WR);
  std::string answer;
  const auto deadline = std::chrono::steady_clock::now() + kCloseWithin;
  char chunk[65536];
  while (true) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    pollfd readable{sock, POLLIN, 0};
    if (left.count() <= 0 || ::poll(&readable, 1, static_cast<int>(left.count())) == 0) {
      std::fprintf(stderr,
                   "the server kept the connection open %lld s after the client stopped "
                   "sending; answered so far:\n%.600s\n",
                   static_cast<long long>(kCloseWithin.count()), answer.c_str());
      std::abort();
    }
    const ssize_t n = ::recv(sock, chunk, sizeof chunk, 0);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;  // closed (a reset after a refusal included)
    answer.append(chunk, static_cast<std::size_t>(n));
  }
  ::close(sock);
  return answer;
}

/// Checks each answer in `answers`, walking from one to the next by Content-Length while the
/// bytes after an answer start another (a chunked one is not walked past: the walk then stops,
/// it does not fail).
void CheckAnswers(std::string_view answers) {
  const auto starts_answer = [&](std::size_t at) {
    return at <= answers.size() && answers.substr(at).rfind("HTTP/1.1 ", 0) == 0;
  };
  bool first = true;
  while (!answers.empty() && (first || starts_answer(0))) {
    first = false;
    const std::size_t head_size = pintag::fuzz::CheckHttpAnswer(answers, /*only_answer=*/false);
    // The next answer starts after the body, or right after the head when this answered HEAD
    // (its Content-Length is the body's a GET would get).
    const std::string_view length =
        pintag::fuzz::HeaderValue(answers.substr(0, head_size - 2), "Content-Length");
    std::size_t next = head_size;
    if (!length.empty() && !starts_answer(next)) {
      next += std::strtoull(std::string(length).c_str(), nullptr, 10);
    }
    if (next > answers.size()) return;
    answers.remove_prefix(next);
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  // The access log would print a line per execution: keep stderr for libFuzzer's reports.
  pintag::server::SetAccessLogEnabled(false);
  pintag::fuzz::ResetRegistry();
  Server();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  pintag::fuzz::ResetRegistry();
  const std::string request =
      pintag::fuzz::WithTokens(std::string(reinterpret_cast<const char*>(data), size));
  CheckAnswers(Exchange(request));
  return 0;
}
