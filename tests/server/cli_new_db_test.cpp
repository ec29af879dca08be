// A `pintag` command given a wrong argument or a bad input file says so before it opens its
// database: no new database is created and seeded (35 MB) only to be left behind.

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "serve_fixture.hpp"

namespace pintag::serve_test {
namespace {

TEST(CliNewDb, AMalformedPincodeIsRefusedBeforeTheDatabaseIsCreated) {
  const TempDir dir;
  const std::string db = dir.file("new.db");
  const CommandResult run = RunPintag("keys lookup abc --db " + db);
  EXPECT_EQ(run.status, 2) << run.out;
  EXPECT_NE(run.out.find("'abc'"), std::string::npos) << run.out;
  EXPECT_EQ(run.out.find("created"), std::string::npos) << run.out;
  EXPECT_FALSE(std::filesystem::exists(db));
}

}  // namespace
}  // namespace pintag::serve_test
