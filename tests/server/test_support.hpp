#pragma once
// Shared fixtures for the HTTP layer tests: a fixed token table and a route table of test routes.

#include <atomic>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "pintag/server/api.hpp"
#include "pintag/server/problem.hpp"
#include "pintag/test/files.hpp"

namespace pintag::server::test {

inline constexpr const char* kAdminToken = "admin-secret";
inline constexpr const char* kCounterToken = "counter-secret";
inline constexpr const char* kScannerToken = "scanner-secret";

inline TokenVerifier FakeVerifier() {
  return [](std::string_view token) -> std::optional<Principal> {
    if (token == kAdminToken) return Principal{"t-admin", Access::kAdmin};
    if (token == kCounterToken) return Principal{"t-counter", Access::kCounter};
    if (token == kScannerToken) return Principal{"t-scanner", Access::kScanner};
    return std::nullopt;
  };
}

/// A metrics counter the file route counts its answers in.
inline constexpr std::string_view kFilesServedCounter = "test_files_served_total";

/// A test route table: an open echo, role-protected routes (an upload, an admin write, a binary
/// file with a suffixed path parameter that counts in kFilesServedCounter), a thrower.
inline Router TestRouter(const std::shared_ptr<Metrics>& metrics) {
  Router router;
  Route echo = MakeRoute(
      "GET", "/api/v1/echo/{word}", Access::kOpen,
      [](const HttpRequest& r) {
        nlohmann::json out = {{"word", r.pathParam("word")}, {"q", r.queryParam("q").value_or("")}};
        return HttpResponse::Json(out.dump());
      },
      "echo");
  echo.query = {{"q", "echoed back"}};
  router.add(std::move(echo));
  Route upload = MakeRoute(
      "POST", "/api/v1/upload", Access::kScanner,
      [](const HttpRequest& r) {
        nlohmann::json out = {{"bytes", r.body.size()},
                              {"parts", r.parts.size()},
                              {"who", r.principal ? r.principal->id : ""},
                              {"type", r.content_type}};
        return HttpResponse::Json(out.dump());
      },
      "upload");
  upload.consumes = {"application/octet-stream", "image/jpeg", "multipart/form-data"};
  router.add(std::move(upload));
  router.add(MakeRoute(
      "PUT", "/api/v1/admin/thing", Access::kAdmin,
      [](const HttpRequest& r) {
        return HttpResponse::Json(nlohmann::json{{"who", r.principal->id}}.dump());
      },
      "admin write"));
  router.add(MakeRoute(
      "GET", "/api/v1/boom", Access::kOpen,
      [](const HttpRequest&) -> HttpResponse { throw std::runtime_error("secret path /etc/db"); },
      "throws"));
  router.add(MakeRoute(
      "GET", "/api/v1/teapot", Access::kOpen,
      [](const HttpRequest&) -> HttpResponse { throw HttpError(418, "short and stout", "Teapot"); },
      "problem"));
  metrics->defineCounter(kFilesServedCounter, "Files the test route served.");
  Route file = MakeRoute(
      "GET", "/api/v1/files/{name}.bin", Access::kCounter,
      [metrics](const HttpRequest& r) {
        metrics->increment(kFilesServedCounter);
        return HttpResponse::Bytes("application/octet-stream", "bytes of " + r.pathParam("name"));
      },
      "a binary file");
  file.produces = {"application/octet-stream"};
  router.add(std::move(file));
  return router;
}

inline HttpRequest Get(std::string path, std::optional<std::string> token = std::nullopt) {
  HttpRequest r;
  r.method = "GET";
  const std::size_t q = path.find('?');
  if (q != std::string::npos) {
    std::string query = path.substr(q + 1);
    path = path.substr(0, q);
    std::size_t start = 0;
    while (start <= query.size()) {
      const std::size_t amp = std::min(query.find('&', start), query.size());
      const std::string pair = query.substr(start, amp - start);
      const std::size_t eq = pair.find('=');
      if (!pair.empty())
        r.query.emplace(pair.substr(0, eq), eq == std::string::npos ? "" : pair.substr(eq + 1));
      start = amp + 1;
    }
  }
  r.path = std::move(path);
  if (token) r.headers.emplace("Authorization", "Bearer " + *token);
  return r;
}

inline nlohmann::json Json(const HttpResponse& r) {
  return nlohmann::json::parse(r.body);
}

using pintag::test::TempDir;

}  // namespace pintag::server::test
