// `pintag scans prune`: old scans taken out of a registry's scan log or a replica's own file,
// the rest left, and the usage errors said before anything is removed.

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "pintag/db/scan_log.hpp"
#include "pintag/db/sqlite.hpp"
#include "serve_fixture.hpp"

namespace pintag::serve_test {
namespace {

/// Appends a scan at each of `times` to the scan log open on `connection`.
void AppendScansAt(db::Connection& connection, const std::vector<std::string>& times) {
  for (const std::string& time : times) {
    ASSERT_TRUE(db::AppendScan(connection, {.scanned_at = time, .result_json = "{}"}).ok()) << time;
  }
}

std::int64_t ScansIn(const std::string& path) {
  db::Connection connection(path, {.create = false, .read_only = true});
  return connection.queryInt64("SELECT count(*) FROM scan_log");
}

TEST(CliScans, PruneRemovesTheScansTakenBeforeADate) {
  const TempDir dir;
  const std::string registry = dir.file("registry.db");
  std::filesystem::copy_file(SeededTemplate(), registry);
  {
    db::Connection connection(registry, {.create = false});
    AppendScansAt(connection, {"2025-12-31T23:59:59.999Z", "2026-01-01T00:00:00.000Z",
                               "2099-01-01T00:00:00.000Z"});
  }
  const CommandResult pruned = RunPintag("scans prune --db " + registry + " --before 2026-01-01");
  EXPECT_EQ(pruned.status, 0) << pruned.out;
  EXPECT_NE(pruned.out.find("removed 1 scan taken before 2026-01-01 from " + registry),
            std::string::npos)
      << pruned.out;
  EXPECT_EQ(ScansIn(registry), 2);
  // Counted back from now: the 2026-01-01 scan is more than 0 days old, the 2099 one is not.
  const CommandResult by_age = RunPintag("scans prune --db " + registry + " --older-than-days 0");
  EXPECT_EQ(by_age.status, 0) << by_age.out;
  EXPECT_NE(by_age.out.find("removed 1 scan taken before "), std::string::npos) << by_age.out;
  EXPECT_EQ(ScansIn(registry), 1);

  // A replica's own file.
  const std::string replica_log = dir.file("replica-scans.db");
  {
    auto opened = db::OpenScanLogFile(replica_log);
    ASSERT_TRUE(opened.ok()) << opened.error().message;
    AppendScansAt(opened.value(), {"2026-02-01T00:00:00.000Z", "2026-04-01T00:00:00.000Z"});
  }
  const CommandResult replica =
      RunPintag("scans prune --scan-log " + replica_log + " --before 2026-03-01");
  EXPECT_EQ(replica.status, 0) << replica.out;
  EXPECT_EQ(ScansIn(replica_log), 1);

  // Said, and nothing removed: a date in another form, both or neither of the paths or the
  // cutoffs; a path that is not there is not made.
  const std::string db = "--db " + registry;
  const std::vector<std::string> usages = {
      db + " --before yesterday", db, "--before 2100-01-01",
      db + " --scan-log " + replica_log + " --before 2100-01-01",
      db + " --before 2100-01-01 --older-than-days 3"};
  for (const std::string& usage : usages) {
    const CommandResult refused = RunPintag("scans prune " + usage);
    EXPECT_EQ(refused.status, 2) << usage << ": " << refused.out;
  }
  EXPECT_EQ(ScansIn(registry), 1);
  const std::string missing = dir.file("missing-scans.db");
  const CommandResult not_there =
      RunPintag("scans prune --scan-log " + missing + " --before 2100-01-01");
  EXPECT_EQ(not_there.status, 1) << not_there.out;
  EXPECT_NE(not_there.out.find("does not exist"), std::string::npos) << not_there.out;
  EXPECT_FALSE(std::filesystem::exists(missing));
}

}  // namespace
}  // namespace pintag::serve_test
