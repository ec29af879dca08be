// A whole HTTP/1.1 request (request line, headers, raw or multipart body) through cpp-httplib's
// parser, the server's limits and auth, the route table and the real handlers, on a seeded
// registry in a temporary file, put back as it was before each input (ResetRegistry). The answer
// must be a well-formed HTTP response, none may be a 500 (an unexpected exception), and every 4xx
// or 5xx must be problem+json: its Content-Type says so whenever it has one (a HEAD answer keeps
// the header and drops the body), and an error without a Content-Type must have no body.
// @ADMIN@, @COUNTER@ and @SCANNER@ in the input become real tokens. The server serves a small
// web directory and trusts 127.0.0.1 (the peer answerRaw reports), 10.0.0.0/8 and fd00::/8 as
// proxies.

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "fuzz_support.hpp"
#include "pintag/server/http_server.hpp"
#include "pintag/server/log.hpp"
#include "pintag/server/trusted_proxies.hpp"

namespace {

pintag::server::HttpServer& Server() {
  static const auto server = [] {
    pintag::server::ServerOptions options;
    options.port = 0;
    // answerRaw's peer is 127.0.0.1: trusted, so X-Forwarded-For is read as behind nginx.
    std::string error;
    auto proxies =
        pintag::server::TrustedProxies::Parse({"127.0.0.1", "10.0.0.0/8", "fd00::/8"}, &error);
    if (!proxies) std::abort();
    options.trusted_proxies = std::move(*proxies);
    return std::make_unique<pintag::server::HttpServer>(pintag::fuzz::Registry().api, options);
  }();
  return *server;
}

/// The value of the head's Content-Type header (cpp-httplib writes it with this spelling, one
/// header a line), or nothing. Matched at a line's start: an echoed header value may hold the
/// same words.
std::optional<std::string_view> ContentType(std::string_view head) {
  constexpr std::string_view kName = "\r\nContent-Type: ";
  const std::size_t at = head.find(kName);
  if (at == std::string_view::npos) return std::nullopt;
  const std::size_t from = at + kName.size();
  return head.substr(from, head.find("\r\n", from) - from);
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
  const std::string answer = Server().answerRaw(request);
  if (answer.empty()) return 0;  // cpp-httplib closed without answering (e.g. no request line)
  if (answer.rfind("HTTP/1.1 ", 0) != 0) std::abort();
  const int status = std::atoi(answer.c_str() + 9);
  if (status < 100 || status > 599) std::abort();
  if (status == 500) std::abort();  // an unexpected exception or storage failure: a finding
  const std::size_t head_end = answer.find("\r\n\r\n");
  if (head_end == std::string::npos) std::abort();
  if (status >= 400) {
    const std::optional<std::string_view> type =
        ContentType(std::string_view(answer).substr(0, head_end + 2));
    const bool has_body = answer.size() > head_end + 4;
    if (type ? *type != "application/problem+json" : has_body) {
      std::fprintf(stderr, "error answered without problem+json:\n%.600s\n", answer.c_str());
      std::abort();
    }
  }
  if (pintag::fuzz::ExpectSuccess() && (status < 200 || status > 299)) {
    std::fprintf(stderr, "expected a 2xx, got:\n%.600s\n", answer.c_str());
    std::abort();
  }
  return 0;
}
