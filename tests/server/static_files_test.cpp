#include "pintag/server/static_files.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include "test_support.hpp"

namespace pintag::server {
namespace {

class StaticFilesTest : public ::testing::Test {
 protected:
  StaticFilesTest() {
    web_ = dir_.path() / "web";
    std::filesystem::create_directories(web_ / "css");
    std::ofstream(web_ / "index.html") << "<h1>PinTag</h1>";
    std::ofstream(web_ / "css" / "site.css") << "body{}";
    std::ofstream(web_ / ".env") << "SECRET=1";
    std::ofstream(dir_.path() / "secret.txt") << "outside";
    std::filesystem::create_symlink(dir_.path() / "secret.txt", web_ / "escape.txt");
    // Found for "/escape" as "/counter" finds counter.html: the root's checks must still hold.
    std::filesystem::create_symlink(dir_.path() / "secret.txt", web_ / "escape.html");
    std::filesystem::create_directory_symlink(dir_.path(), web_ / "up");
  }
  test::TempDir dir_;
  std::filesystem::path web_;
};

TEST_F(StaticFilesTest, ServesFilesAndIndex) {
  const StaticFiles files(web_);
  HttpResponse r = files.serve("/");
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.body, "<h1>PinTag</h1>");
  EXPECT_EQ(r.content_type, "text/html; charset=utf-8");
  r = files.serve("/css/site.css");
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.content_type, "text/css; charset=utf-8");
  EXPECT_EQ(files.serve("/css").status, 404);  // a directory without index.html
  EXPECT_EQ(files.serve("/missing.js").status, 404);
  // A page named without its ".html", as people say it: that page. Nothing else is guessed.
  r = files.serve("/index");
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.body, "<h1>PinTag</h1>");
  EXPECT_EQ(r.content_type, "text/html; charset=utf-8");
  EXPECT_EQ(files.serve("/css/site").status, 404);
  EXPECT_EQ(files.serve("/missing").status, 404);
}

TEST_F(StaticFilesTest, RefusesEveryWayOut) {
  const StaticFiles files(web_);
  for (const std::string& path : std::vector<std::string>{
           std::string("/index.html\0x", 13), std::string("/../secret.txt"),
           "/css/../../secret.txt", "/..", "/./index.html", "/%2e%2e/secret.txt",
           "/%252e%252e/secret.txt", "/..%2fsecret.txt", "/..\\secret.txt", "/.env", "/escape.txt",
           "/up/secret.txt", "/up/secret", "/escape", "//etc/passwd",
           "/\xc0\xae\xc0\xae/secret.txt", "relative", ""}) {
    const HttpResponse r = files.serve(path);
    EXPECT_EQ(r.status, 404) << path;
    EXPECT_EQ(r.content_type, "application/problem+json") << path;
    EXPECT_EQ(r.body.find("outside"), std::string::npos) << path;
    EXPECT_EQ(r.body.find("SECRET"), std::string::npos) << path;
  }
}

TEST_F(StaticFilesTest, SafePathRules) {
  EXPECT_TRUE(StaticFiles::IsSafeUrlPath("/"));
  EXPECT_TRUE(StaticFiles::IsSafeUrlPath("/a/b-c_d.e.js"));
  EXPECT_TRUE(StaticFiles::IsSafeUrlPath("/dir/"));
  EXPECT_FALSE(StaticFiles::IsSafeUrlPath("/a//b"));
  EXPECT_FALSE(StaticFiles::IsSafeUrlPath("/a/../b"));
  EXPECT_FALSE(StaticFiles::IsSafeUrlPath("/a/.git/config"));
  EXPECT_FALSE(StaticFiles::IsSafeUrlPath("/a%2f"));
  EXPECT_FALSE(StaticFiles::IsSafeUrlPath("/a b"));
  EXPECT_FALSE(StaticFiles::IsSafeUrlPath("/" + std::string(2000, 'a')));
}

TEST_F(StaticFilesTest, RootMustExist) {
  EXPECT_THROW(StaticFiles(dir_.path() / "nope"), std::invalid_argument);
}

}  // namespace
}  // namespace pintag::server
