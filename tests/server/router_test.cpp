#include "pintag/server/router.hpp"

#include <gtest/gtest.h>

namespace pintag::server {
namespace {

Handler Ok() {
  return [](const HttpRequest&) { return HttpResponse::Json("{}"); };
}

Router Sample() {
  Router router;
  router.add(MakeRoute("GET", "/api/v1/pincodes/{pin}", Access::kOpen, Ok(), "one"));
  router.add(MakeRoute("GET", "/api/v1/pincodes/search", Access::kOpen, Ok(), "literal"));
  router.add(MakeRoute("POST", "/api/v1/pincodes/{pin}/retire", Access::kAdmin, Ok(), "retire"));
  router.add(MakeRoute("GET", "/api/v1/tags/{pin}.png", Access::kCounter, Ok(), "png"));
  router.add(MakeRoute("GET", "/api/v1/tags/{pin}.svg", Access::kCounter, Ok(), "svg"));
  router.add(MakeRoute("PUT", "/api/v1/sortplans/{name}", Access::kAdmin, Ok(), "put"));
  router.add(MakeRoute("GET", "/api/v1/sortplans/{name}", Access::kOpen, Ok(), "get"));
  return router;
}

TEST(Router, MatchesParametersAndSuffixes) {
  const Router router = Sample();
  RouteMatch m = router.match("GET", "/api/v1/pincodes/110001");
  ASSERT_NE(m.route, nullptr);
  EXPECT_EQ(m.route->summary, "one");
  EXPECT_EQ(m.params.at("pin"), "110001");

  m = router.match("GET", "/api/v1/tags/110001.png");
  ASSERT_NE(m.route, nullptr);
  EXPECT_EQ(m.route->summary, "png");
  EXPECT_EQ(m.params.at("pin"), "110001");
  m = router.match("GET", "/api/v1/tags/110001.svg");
  ASSERT_NE(m.route, nullptr);
  EXPECT_EQ(m.route->summary, "svg");
  EXPECT_EQ(router.match("GET", "/api/v1/tags/110001.gif").route, nullptr);
  EXPECT_EQ(router.match("GET", "/api/v1/tags/.png").route, nullptr);  // empty parameter

  m = router.match("POST", "/api/v1/pincodes/110001/retire");
  ASSERT_NE(m.route, nullptr);
  EXPECT_EQ(m.params.at("pin"), "110001");
}

TEST(Router, LiteralSegmentsWinOverParameters) {
  const Router router = Sample();  // matches point into the router: keep it alive
  const RouteMatch m = router.match("GET", "/api/v1/pincodes/search");
  ASSERT_NE(m.route, nullptr);
  EXPECT_EQ(m.route->summary, "literal");
}

TEST(Router, HeadIsRoutedAsGet) {
  const Router router = Sample();
  const RouteMatch m = router.match("HEAD", "/api/v1/pincodes/110001");
  ASSERT_NE(m.route, nullptr);
  EXPECT_EQ(m.route->method, "GET");
}

TEST(Router, ReportsMethodsAllowedOnAKnownPath) {
  const Router router = Sample();
  RouteMatch m = router.match("DELETE", "/api/v1/sortplans/main");
  EXPECT_EQ(m.route, nullptr);
  EXPECT_EQ(m.allowed_methods, (std::vector<std::string>{"PUT", "GET"}));
  EXPECT_EQ(m.allowed_pattern, "/api/v1/sortplans/{name}");
  m = router.match("GET", "/api/v1/nothing");
  EXPECT_EQ(m.route, nullptr);
  EXPECT_TRUE(m.allowed_methods.empty());
  EXPECT_TRUE(m.allowed_pattern.empty());
  m = router.match("GET", "/api/v1/sortplans/main");
  ASSERT_NE(m.route, nullptr);
  EXPECT_TRUE(m.allowed_pattern.empty());
  // A path both a literal and a parameter pattern match: the literal names it.
  m = router.match("DELETE", "/api/v1/pincodes/search");
  EXPECT_EQ(m.route, nullptr);
  EXPECT_EQ(m.allowed_pattern, "/api/v1/pincodes/search");
  EXPECT_EQ(m.allowed_methods, std::vector<std::string>{"GET"}) << "each method once";
}

TEST(Router, NoMatchForTrailingSlashesOrExtraSegments) {
  const Router router = Sample();
  EXPECT_EQ(router.match("GET", "/api/v1/pincodes/110001/").route, nullptr);
  EXPECT_EQ(router.match("GET", "/api/v1/pincodes/110001/x").route, nullptr);
  EXPECT_EQ(router.match("GET", "api/v1/pincodes/110001").route, nullptr);
  EXPECT_EQ(router.match("GET", "").route, nullptr);
}

TEST(Router, RefusesBadPatternsAndDuplicates) {
  Router router;
  EXPECT_THROW(router.add(MakeRoute("GET", "no-slash", Access::kOpen, Ok(), "")),
               std::invalid_argument);
  EXPECT_THROW(router.add(MakeRoute("GET", "/a/{}", Access::kOpen, Ok(), "")),
               std::invalid_argument);
  EXPECT_THROW(router.add(MakeRoute("GET", "/a/x{p}", Access::kOpen, Ok(), "")),
               std::invalid_argument);
  EXPECT_THROW(router.add(MakeRoute("GET", "/a/{p", Access::kOpen, Ok(), "")),
               std::invalid_argument);
  EXPECT_THROW(router.add(MakeRoute("GET", "/a", Access::kOpen, nullptr, "")),
               std::invalid_argument);
  router.add(MakeRoute("GET", "/a", Access::kOpen, Ok(), ""));
  EXPECT_THROW(router.add(MakeRoute("GET", "/a", Access::kOpen, Ok(), "")), std::invalid_argument);
}

}  // namespace
}  // namespace pintag::server
