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
  pintag::fuzz::CheckHttpAnswer(answer, /*only_answer=*/true);
  return 0;
}
