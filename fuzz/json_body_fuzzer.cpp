// JSON request bodies into every route that takes one, through Api::handle (auth, limits, the
// problem+json wrapper, the real handlers) with an admin token, and into retire, which takes none
// (refused at admission unless empty). The first byte picks the route; the rest is the body.
// Any answer is fine except a 500 (an unexpected exception) or an error that is not
// problem+json. Each input starts from the same registry (ResetRegistry).

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "fuzz_support.hpp"
#include "pintag/server/log.hpp"
#include "pintag/server/problem.hpp"

namespace {

struct Target {
  const char* method;
  const char* path;
};
constexpr std::array<Target, 5> kTargets = {{
    {"POST", "/api/v1/labels"},
    {"POST", "/api/v1/pincodes"},
    {"PUT", "/api/v1/sortplans/fuzz"},
    {"POST", "/api/v1/tokens"},
    {"POST", "/api/v1/pincodes/110001/retire"},
}};

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  pintag::server::SetAccessLogEnabled(false);
  pintag::fuzz::ResetRegistry();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  pintag::fuzz::ResetRegistry();
  const Target& target = kTargets[data[0] % kTargets.size()];
  pintag::server::HttpRequest request;
  request.method = target.method;
  request.path = target.path;
  request.body.assign(reinterpret_cast<const char*>(data) + 1, size - 1);
  request.headers.emplace("Authorization", "Bearer " + pintag::fuzz::Registry().admin_token);
  request.headers.emplace("Content-Type", "application/json");
  request.headers.emplace("Content-Length", std::to_string(request.body.size()));
  const pintag::server::HttpResponse response =
      pintag::fuzz::Registry().api->handle(std::move(request));
  if (response.status == 500) std::abort();
  if (response.status >= 400 && response.content_type != pintag::server::kProblemContentType)
    std::abort();
  if (pintag::fuzz::ExpectSuccess() && (response.status < 200 || response.status > 299)) {
    std::fprintf(stderr, "expected a 2xx from %s %s, got %d: %.300s\n", target.method, target.path,
                 response.status, response.body.c_str());
    std::abort();
  }
  return 0;
}
