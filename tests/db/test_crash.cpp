// A `kill -9` of `pintag import` half-way leaves a sound database holding all or none of it.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <iostream>
#include <thread>

#include "db_test_util.hpp"
#include "pintag/db/registry.hpp"

namespace pintag::db {
namespace {

using test::TempDir;

constexpr int kNewPincodes = 8000;
constexpr int kOfficesPerPincode = 12;

/// An older-layout CSV of 96,000 offices in 8,000 new (9xxxxx) pincodes.
std::string LargeCsv() {
  std::string csv =
      "officename,pincode,officeType,Deliverystatus,divisionname,regionname,circlename,Taluk,"
      "Districtname,statename\n";
  for (int p = 0; p < kNewPincodes; ++p) {
    const std::string pincode = std::to_string(900000 + p * 7);
    for (int o = 0; o < kOfficesPerPincode; ++o) {
      csv += "Crash Test Office " + std::to_string(o) + " B.O," + pincode +
             ",BO,Delivery,Test Division,Test Region,Test Circle,Test Taluk,Test District,"
             "Test State\n";
    }
  }
  return csv;
}

pid_t Spawn(const std::vector<std::string>& args) {
  std::vector<char*> argv;
  argv.reserve(args.size() + 1);
  for (const std::string& arg : args) argv.push_back(const_cast<char*>(arg.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
  pid_t pid = -1;
  const int error = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  return error == 0 ? pid : -1;
}

std::uintmax_t FileSize(const std::string& path) {
  std::error_code error;
  const auto size = std::filesystem::file_size(path, error);
  return error ? 0 : size;
}

enum class Outcome { kNone, kAll, kTorn };

/// Checks the database after the child died: sound, and all or none of the import.
Outcome Inspect(const std::string& path, const RegistryCounts& before) {
  Connection connection = test::OpenExisting(path);
  EXPECT_EQ(test::IntegrityCheck(connection), "ok");
  EXPECT_EQ(connection.queryInt64("SELECT count(*) FROM pragma_foreign_key_check"), 0);
  const RegistryCounts after = CountRegistry(connection).value();
  if (after.offices == before.offices && after.pincodes_active == before.pincodes_active &&
      after.keys_allocated == before.keys_allocated) {
    return Outcome::kNone;
  }
  if (after.offices == before.offices + std::int64_t{kNewPincodes} * kOfficesPerPincode &&
      after.pincodes_active == before.pincodes_active + kNewPincodes &&
      after.keys_allocated == before.keys_allocated + kNewPincodes) {
    return Outcome::kAll;
  }
  ADD_FAILURE() << "torn import: " << after.offices << " offices, " << after.pincodes_active
                << " pincodes";
  return Outcome::kTorn;
}

TEST(Crash, KillNineDuringImportLeavesAllOrNone) {
  if (test::PintagExe().empty()) GTEST_SKIP() << "no pintag executable in this build";
  TempDir dir;
  const std::string csv = test::WriteFile(dir.file("large.csv"), LargeCsv());
  RegistryCounts before;
  {
    Connection connection = test::OpenExisting(test::SeededTemplate());
    before = CountRegistry(connection).value();
  }

  // Kill once the import's uncommitted pages have reached the WAL (so it is mid-transaction),
  // then at a few fixed delays, then let one run to the end.
  int none = 0;
  int all = 0;
  for (int trial = 0; trial < 4; ++trial) {
    const std::string db = test::CopyOfSeeded(dir, "trial" + std::to_string(trial) + ".db");
    const pid_t pid = Spawn({test::PintagExe(), "import", csv, "--db", db});
    ASSERT_GT(pid, 0);
    const auto start = std::chrono::steady_clock::now();
    if (trial == 0) {
      while (FileSize(db + "-wal") < (1u << 20) &&
             std::chrono::steady_clock::now() - start < std::chrono::seconds(20)) {
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
      }
    } else if (trial < 3) {
      std::this_thread::sleep_for(std::chrono::milliseconds(trial == 1 ? 300 : 650));
    }
    if (trial < 3) {
      kill(pid, SIGKILL);
    }
    int status = 0;
    ASSERT_EQ(waitpid(pid, &status, 0), pid);
    if (trial < 3 && WIFSIGNALED(status)) {
      EXPECT_EQ(WTERMSIG(status), SIGKILL);
    } else {
      EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "trial " << trial;
    }
    const Outcome outcome = Inspect(db, before);
    none += outcome == Outcome::kNone;
    all += outcome == Outcome::kAll;
    std::cerr << "trial " << trial << ": " << (WIFSIGNALED(status) ? "killed" : "finished")
              << " after "
              << std::chrono::duration_cast<std::chrono::milliseconds>(
                     std::chrono::steady_clock::now() - start)
                     .count()
              << " ms, import "
              << (outcome == Outcome::kNone  ? "absent"
                  : outcome == Outcome::kAll ? "complete"
                                             : "TORN")
              << "\n";
    if (trial == 0) {
      EXPECT_EQ(outcome, Outcome::kNone) << "killed mid-transaction";
    }
    if (trial == 3) {
      EXPECT_EQ(outcome, Outcome::kAll) << "the uninterrupted import";
    }
  }
  EXPECT_GE(none, 1);
  EXPECT_GE(all, 1);
}

}  // namespace
}  // namespace pintag::db
