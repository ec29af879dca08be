#include <gtest/gtest.h>

#include "test_support.hpp"

namespace pintag::server {
namespace {

TEST(OpenApi, DescribesEveryRouteOfTheTable) {
  auto metrics = std::make_shared<Metrics>();
  const Api api(test::TestRouter(metrics), test::FakeVerifier(), nullptr, metrics);
  const HttpResponse r = api.handle(test::Get("/openapi.json"));
  ASSERT_EQ(r.status, 200);
  const nlohmann::json doc = nlohmann::json::parse(r.body);
  EXPECT_EQ(doc["openapi"], "3.1.0");
  EXPECT_EQ(doc["info"]["title"], "PinTag");
  int operations = 0;
  for (const Route& route : api.router().routes()) {
    std::string method = route.method;
    for (char& c : method) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    ASSERT_TRUE(doc["paths"].contains(route.pattern)) << route.pattern;
    ASSERT_TRUE(doc["paths"][route.pattern].contains(method))
        << route.method << " " << route.pattern;
    const nlohmann::json& op = doc["paths"][route.pattern][method];
    EXPECT_EQ(op.contains("security"), route.access != Access::kOpen) << route.pattern;
    EXPECT_TRUE(op["responses"].contains("4XX"));
    ++operations;
  }
  int listed = 0;
  for (const auto& [path, item] : doc["paths"].items()) listed += static_cast<int>(item.size());
  EXPECT_EQ(listed, operations);
  for (const char* path : {"/livez", "/readyz", "/metrics", "/openapi.json",
                           "/api/v1/files/{name}.bin", "/api/v1/upload", "/api/v1/echo/{word}"}) {
    EXPECT_TRUE(doc["paths"].contains(path)) << path;
  }
  const nlohmann::json& file = doc["paths"]["/api/v1/files/{name}.bin"]["get"];
  EXPECT_EQ(file["parameters"][0]["name"], "name");
  EXPECT_EQ(file["parameters"][0]["in"], "path");
  EXPECT_TRUE(file["responses"]["200"]["content"].contains("application/octet-stream"));
  EXPECT_EQ(file["x-pintag-role"], "counter");
  EXPECT_EQ(doc["paths"]["/livez"]["get"]["x-pintag-role"], "open");
  EXPECT_EQ(doc["components"]["securitySchemes"]["bearer"]["scheme"], "bearer");
}

// Each listed operation answers (with an admin token): nothing in the
// document is a 404 or 405.
TEST(OpenApi, EveryListedOperationAnswers) {
  auto metrics = std::make_shared<Metrics>();
  const Api api(test::TestRouter(metrics), test::FakeVerifier(), nullptr, metrics);
  const nlohmann::json doc = nlohmann::json::parse(api.handle(test::Get("/openapi.json")).body);
  for (const auto& [pattern, item] : doc["paths"].items()) {
    for (const auto& [method, op] : item.items()) {
      std::string path = pattern;
      for (const auto& [from, to] :
           {std::pair<std::string, std::string>{"{name}", "n"}, {"{word}", "w"}}) {
        for (std::size_t at = path.find(from); at != std::string::npos; at = path.find(from))
          path.replace(at, from.size(), to);
      }
      HttpRequest r = test::Get(path, test::kAdminToken);
      r.method.clear();
      for (char c : method)
        r.method += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
      if (op.contains("requestBody")) {
        const std::string type = op["requestBody"]["content"].begin().key();
        r.headers.emplace("Content-Type", type);
        r.body = type == "application/json" ? "{}" : "x";
        r.headers.emplace("Content-Length", std::to_string(r.body.size()));
      }
      const HttpResponse response = api.handle(r);
      EXPECT_NE(response.status, 404) << method << " " << path << ": " << response.body;
      EXPECT_NE(response.status, 405) << method << " " << path;
      EXPECT_NE(response.status, 401) << method << " " << path;
    }
  }
}

}  // namespace
}  // namespace pintag::server
