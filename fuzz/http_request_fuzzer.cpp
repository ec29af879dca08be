// A whole HTTP/1.1 request (request line, headers, raw or multipart body) through cpp-httplib's
// parser, the server's limits and auth, the route table and the real handlers, on a seeded
// registry in a temporary file. The answer must be a well-formed HTTP response, and any 4xx or
// 5xx must be problem+json, and none may be a 500 (an unexpected exception). @ADMIN@, @COUNTER@ and
// @SCANNER@ in the input become real tokens.

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <string>

#include "fuzz_support.hpp"
#include "pintag/server/http_server.hpp"
#include "pintag/server/log.hpp"

namespace {

pintag::server::HttpServer& Server() {
  static const auto server = [] {
    pintag::server::ServerOptions options;
    options.port = 0;
    return std::make_unique<pintag::server::HttpServer>(pintag::fuzz::Registry().api, options);
  }();
  return *server;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  // The access log would print a line per execution: keep stderr for libFuzzer's reports.
  pintag::server::SetAccessLogEnabled(false);
  Server();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
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
  if (status >= 400 && answer.compare(head_end + 4, 1, "{") == 0 &&
      answer.substr(0, head_end).find("Content-Type: application/problem+json") ==
          std::string::npos) {
    std::abort();  // an error answered with a JSON body that is not a problem
  }
  return 0;
}
