// Handler-level tests: the whole request path (routing, auth, limits, problem+json, metrics)
// without sockets, through Api::handle.

#include <gtest/gtest.h>

#include "test_support.hpp"

namespace pintag::server {
namespace {

using test::Get;
using test::Json;

class ApiTest : public ::testing::Test {
 protected:
  ApiTest()
      : metrics_(std::make_shared<Metrics>()),
        api_(
            test::TestRouter(metrics_), test::FakeVerifier(), [this] { return health_; }, metrics_,
            ApiOptions{1024, std::nullopt, {}}) {}

  void expectProblem(const HttpResponse& r, int status) {
    EXPECT_EQ(r.status, status) << r.body;
    EXPECT_EQ(r.content_type, "application/problem+json");
    const nlohmann::json body = Json(r);
    EXPECT_EQ(body["status"], status);
    EXPECT_EQ(body["type"], "about:blank");
    EXPECT_TRUE(body["title"].is_string() && !body["title"].get<std::string>().empty());
    EXPECT_TRUE(body["detail"].is_string() && !body["detail"].get<std::string>().empty());
  }

  std::optional<std::string> health_;
  std::shared_ptr<Metrics> metrics_;
  Api api_;
};

TEST_F(ApiTest, RoutesWithPathAndQueryParameters) {
  const HttpResponse r = api_.handle(Get("/api/v1/echo/hello?q=world"));
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(Json(r)["word"], "hello");
  EXPECT_EQ(Json(r)["q"], "world");
}

// A misspelt query parameter was ignored (a label printed the default plan's bins), and of one
// given twice the first was taken. A route takes the parameters it documents, each once.
TEST_F(ApiTest, QueryParametersARouteDoesNotTakeOrGivenTwiceAreRefused) {
  HttpResponse r = api_.handle(Get("/api/v1/echo/hello?qq=world"));
  expectProblem(r, 400);
  EXPECT_EQ(Json(r)["detail"], "unknown query parameter 'qq'; this route takes q");
  r = api_.handle(Get("/api/v1/echo/hello?q=a&q=b"));
  expectProblem(r, 400);
  EXPECT_EQ(Json(r)["detail"], "the query parameter 'q' is given 2 times; give it once");
  r = api_.handle(Get("/livez?verbose=1"));
  expectProblem(r, 400);
  EXPECT_EQ(Json(r)["detail"], "unknown query parameter 'verbose'; this route takes none");
  EXPECT_EQ(api_.handle(Get("/api/v1/echo/hello?q=")).status, 200);
}

TEST_F(ApiTest, UnknownPathIs404Problem) {
  expectProblem(api_.handle(Get("/api/v1/nope")), 404);
}

TEST_F(ApiTest, WrongMethodIs405ProblemWithAllow) {
  HttpRequest r = Get("/livez");
  r.method = "POST";
  const HttpResponse response = api_.handle(r);
  expectProblem(response, 405);
  ASSERT_EQ(response.headers.size(), 1U);
  EXPECT_EQ(response.headers[0].first, "Allow");
  EXPECT_EQ(response.headers[0].second, "GET, HEAD");
}

TEST_F(ApiTest, MissingTokenIs401WithChallenge) {
  HttpRequest r = Get("/api/v1/upload");
  r.method = "POST";
  const HttpResponse response = api_.handle(r);
  expectProblem(response, 401);
  ASSERT_FALSE(response.headers.empty());
  EXPECT_EQ(response.headers[0].first, "WWW-Authenticate");
  EXPECT_EQ(response.headers[0].second, R"(Bearer realm="pintag")");
}

TEST_F(ApiTest, BadTokensAre401) {
  for (const std::string header : {"Bearer nope", "Basic YWRtaW46YWRtaW4=", "Bearer", "Bearer  ",
                                   "admin-secret", "Token admin-secret"}) {
    HttpRequest r = Get("/api/v1/admin/thing");
    r.method = "PUT";
    r.headers.emplace("Authorization", header);
    expectProblem(api_.handle(r), 401);
  }
}

TEST_F(ApiTest, WrongRoleIs403AndAdminMayDoAnything) {
  HttpRequest r = Get("/api/v1/admin/thing", test::kCounterToken);
  r.method = "PUT";
  expectProblem(api_.handle(r), 403);
  r = Get("/api/v1/upload", test::kCounterToken);
  r.method = "POST";
  expectProblem(api_.handle(r), 403);

  r = Get("/api/v1/admin/thing", test::kAdminToken);
  r.method = "PUT";
  HttpResponse ok = api_.handle(r);
  EXPECT_EQ(ok.status, 200) << ok.body;
  EXPECT_EQ(Json(ok)["who"], "t-admin");
  r = Get("/api/v1/upload", test::kScannerToken);
  r.method = "POST";
  ok = api_.handle(r);
  EXPECT_EQ(ok.status, 200) << ok.body;
  EXPECT_EQ(Json(ok)["who"], "t-scanner");
}

TEST_F(ApiTest, SchemeIsCaseInsensitive) {
  HttpRequest r = Get("/api/v1/upload");
  r.method = "POST";
  r.headers.emplace("authorization", std::string("bEaReR ") + test::kScannerToken);
  EXPECT_EQ(api_.handle(r).status, 200);
}

TEST_F(ApiTest, OversizedBodyIs413BeforeAndAfterReading) {
  HttpRequest r = Get("/api/v1/upload", test::kScannerToken);
  r.method = "POST";
  r.headers.emplace("Content-Type", "application/octet-stream");
  r.body = std::string(1025, 'x');
  expectProblem(api_.handle(r), 413);
  // Declared too large: refused from the headers alone.
  HeaderMap headers = r.headers;
  headers.emplace("Content-Length", "1025");
  const Admission admission = api_.admit("POST", "/api/v1/upload", headers);
  ASSERT_TRUE(admission.rejection.has_value());
  EXPECT_EQ(admission.rejection->status, 413);
  headers.erase("Content-Length");
  headers.emplace("Content-Length", "99999999999999999999999");
  EXPECT_EQ(api_.admit("POST", "/api/v1/upload", headers).rejection->status, 413);
  headers.erase("Content-Length");
  headers.emplace("Content-Length", "12abc");
  EXPECT_EQ(api_.admit("POST", "/api/v1/upload", headers).rejection->status, 400);
  r.body = std::string(1024, 'x');
  EXPECT_EQ(api_.handle(r).status, 200);
}

TEST_F(ApiTest, AuthIsCheckedBeforeTheBodyLimit) {
  HeaderMap headers;
  headers.emplace("Content-Length", "999999");
  EXPECT_EQ(api_.admit("POST", "/api/v1/upload", headers).rejection->status, 401);
}

TEST_F(ApiTest, WrongContentTypeIs415) {
  HttpRequest r = Get("/api/v1/upload", test::kScannerToken);
  r.method = "POST";
  r.headers.emplace("Content-Type", "text/plain");
  r.headers.emplace("Content-Length", "3");
  r.body = "abc";
  expectProblem(api_.handle(r), 415);
  r.headers.erase("Content-Type");
  r.headers.emplace("Content-Type", "IMAGE/JPEG; foo=bar");
  const HttpResponse ok = api_.handle(r);
  EXPECT_EQ(ok.status, 200);
  EXPECT_EQ(Json(ok)["type"], "image/jpeg");
}

TEST_F(ApiTest, ExceptionsBecome500WithoutLeakingTheMessage) {
  const HttpResponse r = api_.handle(Get("/api/v1/boom"));
  expectProblem(r, 500);
  EXPECT_EQ(r.body.find("/etc/db"), std::string::npos);
}

TEST_F(ApiTest, HttpErrorBecomesItsProblem) {
  const HttpResponse r = api_.handle(Get("/api/v1/teapot"));
  expectProblem(r, 418);
  EXPECT_EQ(Json(r)["title"], "Teapot");
  EXPECT_EQ(Json(r)["detail"], "short and stout");
}

TEST_F(ApiTest, ErrorStatusWithEmptyBodyBecomesAProblem) {
  const HttpResponse r =
      InvokeHandler([](const HttpRequest&) { return HttpResponse::Json("", 409); }, {});
  expectProblem(r, 409);
  EXPECT_EQ(Json(r)["title"], "Conflict");
}

TEST_F(ApiTest, LivezAndReadyz) {
  EXPECT_EQ(api_.handle(Get("/livez")).status, 200);
  EXPECT_EQ(Json(api_.handle(Get("/readyz")))["status"], "ready");
  health_ = "database unreachable: disk I/O error";
  const HttpResponse r = api_.handle(Get("/readyz"));
  expectProblem(r, 503);
  EXPECT_EQ(Json(r)["detail"], "database unreachable: disk I/O error");
  EXPECT_EQ(api_.handle(Get("/livez")).status, 200);  // alive, just not ready
}

TEST_F(ApiTest, CountsRequestsByRouteAndStatus) {
  api_.handle(Get("/livez"));
  api_.handle(Get("/livez"));
  api_.handle(Get("/api/v1/echo/a"));
  api_.handle(Get("/api/v1/nope"));
  api_.handle(Get("/api/v1/files/x.bin"));
  HttpRequest wrong_method = Get("/api/v1/echo/b");
  wrong_method.method = "DELETE";
  api_.handle(wrong_method);
  EXPECT_EQ(metrics_->requestCount("/livez", "GET", 200), 2);
  EXPECT_EQ(metrics_->requestCount("/api/v1/echo/{word}", "DELETE", 405), 1)
      << "a wrong method is counted under the route its path matched";
  EXPECT_EQ(metrics_->requestCount("unmatched", "DELETE", 405), 0);
  EXPECT_EQ(metrics_->requestCount("/api/v1/echo/{word}", "GET", 200), 1);
  EXPECT_EQ(metrics_->requestCount("unmatched", "GET", 404), 1);
  EXPECT_EQ(metrics_->requestCount("/api/v1/files/{name}.bin", "GET", 401), 1);
  const std::string text = api_.handle(Get("/metrics")).body;
  EXPECT_NE(text.find(R"(pintag_http_requests_total{route="/livez",method="GET",status="200"} 2)"),
            std::string::npos)
      << text;
}

}  // namespace
}  // namespace pintag::server
