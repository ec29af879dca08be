#include "pintag/server/problem.hpp"

#include <nlohmann/json.hpp>

#include "pintag/server/log.hpp"

namespace pintag::server {

HttpError::HttpError(int status, std::string detail, std::string title, std::string type)
    : problem_{status, std::move(title), std::move(detail),
               type.empty() ? std::string("about:blank") : std::move(type)} {}

std::string_view StatusTitle(int status) {
  switch (status) {
    case 400:
      return "Bad Request";
    case 401:
      return "Unauthorized";
    case 403:
      return "Forbidden";
    case 404:
      return "Not Found";
    case 405:
      return "Method Not Allowed";
    case 406:
      return "Not Acceptable";
    case 408:
      return "Request Timeout";
    case 409:
      return "Conflict";
    case 410:
      return "Gone";
    case 411:
      return "Length Required";
    case 412:
      return "Precondition Failed";
    case 413:
      return "Content Too Large";
    case 414:
      return "URI Too Long";
    case 415:
      return "Unsupported Media Type";
    case 416:
      return "Range Not Satisfiable";
    case 422:
      return "Unprocessable Content";
    case 429:
      return "Too Many Requests";
    case 431:
      return "Request Header Fields Too Large";
    case 500:
      return "Internal Server Error";
    case 501:
      return "Not Implemented";
    case 503:
      return "Service Unavailable";
    case 505:
      return "HTTP Version Not Supported";
    case 507:
      return "Insufficient Storage";
    default:
      return "Error";
  }
}

HttpResponse ProblemResponse(Problem problem) {
  if (problem.title.empty()) problem.title = std::string(StatusTitle(problem.status));
  if (problem.type.empty()) problem.type = "about:blank";
  nlohmann::json body = {{"type", problem.type},
                         {"title", problem.title},
                         {"status", problem.status},
                         {"detail", problem.detail}};
  for (const auto& [name, value] : problem.numbers) {
    if (!body.contains(name)) body[name] = value;
  }
  // Replace invalid UTF-8 (details may quote user input) instead of throwing.
  HttpResponse response{problem.status,
                        std::string(kProblemContentType),
                        body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace),
                        {}};
  if (problem.retry_after_seconds > 0) {
    response.headers.emplace_back("Retry-After", std::to_string(problem.retry_after_seconds));
  }
  return response;
}

HttpResponse ProblemResponse(int status, std::string detail) {
  return ProblemResponse(Problem{status, {}, std::move(detail), "about:blank"});
}

HttpResponse BodyTooLargeResponse(std::size_t max_body_bytes) {
  Problem problem{
      413, {}, "the request body may be at most " + std::to_string(max_body_bytes) + " bytes"};
  problem.numbers = {{"max_body_bytes", static_cast<std::int64_t>(max_body_bytes)}};
  return ProblemResponse(std::move(problem));
}

HttpResponse InvokeHandler(const Handler& handler, const HttpRequest& request) {
  try {
    HttpResponse response = handler(request);
    if (response.status >= 400 && response.body.empty()) {
      return ProblemResponse(response.status, std::string(StatusTitle(response.status)));
    }
    return response;
  } catch (const HttpError& error) {
    if (error.problem().status >= 500) {
      LogRequestError(request.request_id, request.method + " " + request.path + ": " +
                                              std::to_string(error.problem().status) + " " +
                                              error.problem().detail);
    }
    return ProblemResponse(error.problem());
  } catch (const std::exception& error) {
    // The message may hold paths or SQL: it belongs in the server log, not the answer.
    LogRequestError(request.request_id, request.method + " " + request.path +
                                            ": unexpected exception: " + error.what());
    return ProblemResponse(500, "the server failed to handle this request");
  } catch (...) {
    LogRequestError(request.request_id,
                    request.method + " " + request.path + ": unexpected non-standard exception");
    return ProblemResponse(500, "the server failed to handle this request");
  }
}

}  // namespace pintag::server
