#pragma once
// RFC 9457 problem details: every 4xx/5xx answer is application/problem+json with type, title,
// status and detail.

#include <cstdint>
#include <exception>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "pintag/server/http_types.hpp"

namespace pintag::server {

inline constexpr std::string_view kProblemContentType = "application/problem+json";

struct Problem {
  int status = 500;
  std::string title;   ///< short, the same for every occurrence of this kind of problem
  std::string detail;  ///< this occurrence, fit to show a user
  std::string type = "about:blank";  ///< a URI naming the kind; about:blank means "see status"
  /// When above 0, the answer carries Retry-After with it: the problem is expected to pass
  /// (a busy database, a full write gate) and the client may ask again after that many seconds.
  int retry_after_seconds = 0;
  /// Extension members (RFC 9457 §3.2): numbers a client can act on without reading `detail`,
  /// such as the limit a request went over. A name must not be one of the four above.
  std::vector<std::pair<std::string, std::int64_t>> numbers = {};
};

/// Thrown by handlers (or returned as a value through ProblemResponse) to answer a problem.
class HttpError : public std::exception {
 public:
  HttpError(int status, std::string detail, std::string title = {}, std::string type = {});
  explicit HttpError(Problem problem) : problem_(std::move(problem)) {}
  const Problem& problem() const { return problem_; }
  const char* what() const noexcept override { return problem_.detail.c_str(); }

 private:
  Problem problem_;
};

/// The standard reason phrase of a status ("Not Found"), or "Error".
std::string_view StatusTitle(int status);

/// A problem+json response; an empty title becomes StatusTitle(status).
HttpResponse ProblemResponse(Problem problem);
HttpResponse ProblemResponse(int status, std::string detail);
/// 413 for a body over the limit, the limit given as the number `max_body_bytes` too.
HttpResponse BodyTooLargeResponse(std::size_t max_body_bytes);

/// The one wrapper: runs `handler`, turning HttpError into its problem, any other exception into
/// a 500 problem (details are not leaked), and an error status with an empty body into a problem.
/// Every 5xx, with its exception's message, goes to the server log under the request's id.
HttpResponse InvokeHandler(const Handler& handler, const HttpRequest& request);

}  // namespace pintag::server
