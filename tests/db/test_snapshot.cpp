// Registry snapshots: the registry version moves with every change a replica must see and with
// nothing else; a snapshot is a consistent, self-contained, read-only-openable copy that replaces
// its target atomically.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <thread>
#include <vector>

#include "db_test_util.hpp"
#include "pintag/db/registry.hpp"
#include "pintag/db/scan_log.hpp"
#include "pintag/db/snapshot.hpp"
#include "pintag/db/sort_plan.hpp"
#include "pintag/db/tokens.hpp"
#include "pintag/test/test_office.hpp"

namespace pintag::db {
namespace {

using test::TempDir;

std::int64_t VersionOf(Connection& connection) {
  auto version = RegistryVersion(connection);
  EXPECT_TRUE(version.ok()) << version.error().message;
  return version.ok() ? *version : -1;
}

std::string KeysCsv(Connection& connection) {
  auto rows = ListKeys(connection);
  EXPECT_TRUE(rows.ok());
  std::string out;
  if (!rows.ok()) return out;
  for (const KeyRow& row : *rows) {
    out += row.pincode.str() + "," + std::to_string(row.key.value()) + "," + ToString(row.status) +
           "\n";
  }
  return out;
}

using pintag::test::TestOffice;

TEST(RegistryVersion, EveryChangeAReplicaServesIncreasesIt) {
  TempDir dir;
  Connection connection = test::OpenExisting(test::CopyOfSeeded(dir));
  std::int64_t last = VersionOf(connection);
  EXPECT_GE(last, 1);
  const auto increased = [&](const char* what) {
    const std::int64_t now = VersionOf(connection);
    EXPECT_GT(now, last) << what;
    last = now;
  };
  ASSERT_TRUE(AddPincode(connection, Pincode(999001), {TestOffice("Snapshot Nagar")}).ok());
  increased("adding a pincode");
  ASSERT_TRUE(RetirePincode(connection, Pincode(999001)).ok());
  increased("retiring a pincode");
  ASSERT_TRUE(SavePlan(connection, {"hub", "floor", "", {{"56", "south"}}}).ok());
  increased("saving a sort plan");
  ASSERT_TRUE(DeletePlan(connection, "hub").ok());
  increased("deleting a sort plan");
  auto token = CreateToken(connection, Role::kScanner, "handheld");
  ASSERT_TRUE(token.ok());
  increased("creating a token");
  ASSERT_TRUE(RevokeToken(connection, token->info.id).ok());
  increased("revoking a token");
}

TEST(RegistryVersion, ReadsAndTheScanLogLeaveItAlone) {
  TempDir dir;
  Connection connection = test::OpenExisting(test::CopyOfSeeded(dir));
  const std::int64_t before = VersionOf(connection);
  ASSERT_TRUE(LookupPincode(connection, Pincode(110001)).ok());
  ASSERT_TRUE(Search(connection, {.name_prefix = "Conn", .limit = 5}).ok());
  ASSERT_TRUE(Route(connection, Pincode(560001), kDefaultPlanName).ok());
  ASSERT_TRUE(AppendScan(connection, {.image_bytes = 10, .result_json = "{}"}).ok());
  ASSERT_FALSE(AddPincode(connection, Pincode(110001)).ok());  // refused: nothing committed
  EXPECT_EQ(VersionOf(connection), before);
}

TEST(Snapshot, HoldsTheRegistryAndItsVersionAndOpensReadOnly) {
  TempDir dir;
  Connection live = test::OpenExisting(test::CopyOfSeeded(dir));
  ASSERT_TRUE(AddPincode(live, Pincode(999002), {TestOffice("Copy Nagar")}).ok());
  ASSERT_TRUE(AppendScan(live, {.image_bytes = 10, .result_json = R"({"tags": []})"}).ok());
  const std::string out = dir.file("snapshot.db");

  const auto written = WriteSnapshot(live, out);
  ASSERT_TRUE(written.ok()) << written.error().message;
  EXPECT_EQ(written->path, out);
  EXPECT_EQ(written->registry_version, VersionOf(live));
  EXPECT_EQ(written->bytes, std::filesystem::file_size(out));
  // One file: no WAL beside it, and no temporary left in the directory.
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
    names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"registry.db", "registry.db-shm", "registry.db-wal",
                                             "snapshot.db"}));

  ::chmod(out.c_str(), 0444);
  auto opened = OpenDatabase(out, {.create = false, .read_only = true});
  ASSERT_TRUE(opened.ok()) << opened.error().message;
  Connection& copy = opened.value().connection;
  EXPECT_EQ(KeysCsv(copy), KeysCsv(live));
  EXPECT_EQ(LookupPincode(copy, Pincode(999002)).value().offices.at(0).name, "Copy Nagar");
  EXPECT_EQ(VersionOf(copy), written->registry_version);
  EXPECT_EQ(copy.queryInt64("SELECT count(*) FROM scan_log"), 0);  // each server keeps its own
  EXPECT_EQ(copy.queryInt64("SELECT count(*) FROM sort_rules"),
            live.queryInt64("SELECT count(*) FROM sort_rules"));
  Statement mode = copy.prepare("PRAGMA journal_mode");
  ASSERT_TRUE(mode.step());
  EXPECT_EQ(mode.getText(0), "delete");
  EXPECT_EQ(test::IntegrityCheck(copy), "ok");

  const auto verified = VerifySnapshot(out);
  ASSERT_TRUE(verified.ok()) << verified.error().message;
  EXPECT_EQ(verified->registry_version, written->registry_version);
  // Every table, index and trigger of the source, and its schema version.
  const auto schema = [](Connection& connection) {
    std::string listed;
    Statement objects = connection.prepare(
        "SELECT type || ' ' || name || ': ' || coalesce(sql, '') FROM sqlite_master ORDER BY "
        "type, name");
    while (objects.step()) listed += objects.getText(0) + "\n";
    return listed + "user_version " + std::to_string(connection.queryInt64("PRAGMA user_version"));
  };
  EXPECT_EQ(schema(copy), schema(live));
  // The live database is still in WAL mode (the copy's journal mode is set on its own file).
  Statement live_mode = live.prepare("PRAGMA journal_mode");
  ASSERT_TRUE(live_mode.step());
  EXPECT_EQ(live_mode.getText(0), "wal");
}

// The snapshot was the backup API's copy of every page, the scan log's too, then deleted and
// vacuumed: a primary's publication took time and room in proportion to its scan log (5.4 s
// against 0.4 s at a million scans). It is built from the registry's rows alone now: the same
// file whatever the scan log holds.
TEST(Snapshot, IsTheSameFileWhateverTheScanLogHolds) {
  TempDir dir;
  Connection live = test::OpenExisting(test::CopyOfSeeded(dir));
  const auto before = WriteSnapshot(live, dir.file("before.db"));
  ASSERT_TRUE(before.ok()) << before.error().message;
  std::vector<ScanRecord> scans(20'000, ScanRecord{.image_bytes = 500'000,
                                                   .result_json = R"({"tags": [], "note": ")" +
                                                                  std::string(400, 'x') + "\"}"});
  const auto appended = AppendScans(live, scans);
  ASSERT_TRUE(appended.ok()) << appended.error().message;
  ASSERT_EQ(appended->written, scans.size());
  const auto after = WriteSnapshot(live, dir.file("after.db"));
  ASSERT_TRUE(after.ok()) << after.error().message;
  EXPECT_EQ(after->registry_version, before->registry_version);  // scans are not the registry
  EXPECT_EQ(after->bytes, before->bytes);
  EXPECT_EQ(test::ReadFile(dir.file("after.db")), test::ReadFile(dir.file("before.db")));
}

TEST(Snapshot, ReplacesTheTargetAtomicallyWhileAReaderHoldsTheOldOne) {
  TempDir dir;
  Connection live = test::OpenExisting(test::CopyOfSeeded(dir));
  const std::string out = dir.file("snapshot.db");
  const auto first = WriteSnapshot(live, out);
  ASSERT_TRUE(first.ok()) << first.error().message;
  Connection old_reader(out, {.create = false, .read_only = true});
  ASSERT_EQ(old_reader.queryInt64("SELECT count(*) FROM pincodes WHERE pincode = 999003"), 0);

  ASSERT_TRUE(AddPincode(live, Pincode(999003), {TestOffice("Later Nagar")}).ok());
  const auto second = WriteSnapshot(live, out);
  ASSERT_TRUE(second.ok()) << second.error().message;
  EXPECT_GT(second->registry_version, first->registry_version);

  // The reader opened before the rename still reads the first snapshot, whole.
  EXPECT_EQ(old_reader.queryInt64("SELECT count(*) FROM pincodes WHERE pincode = 999003"), 0);
  EXPECT_EQ(VersionOf(old_reader), first->registry_version);
  EXPECT_EQ(test::IntegrityCheck(old_reader), "ok");
  Connection new_reader(out, {.create = false, .read_only = true});
  EXPECT_EQ(new_reader.queryInt64("SELECT count(*) FROM pincodes WHERE pincode = 999003"), 1);
  EXPECT_EQ(VersionOf(new_reader), second->registry_version);
}

TEST(Snapshot, IsConsistentWhileAWriterCommits) {
  TempDir dir;
  const std::string path = test::CopyOfSeeded(dir);
  const std::int64_t seeded_pincodes = 19159;
  std::atomic<bool> stop{false};
  std::atomic<int> added{0};
  std::thread writer([&] {
    Connection connection = test::OpenExisting(path);
    for (int i = 0; i < 400 && !stop; ++i) {
      const auto result = AddPincode(connection, Pincode(990000 + i),
                                     {TestOffice("A"), TestOffice("B"), TestOffice("C")});
      if (!result.ok()) ADD_FAILURE() << result.error().message;
      ++added;
    }
  });
  Connection source = test::OpenExisting(path);
  std::int64_t last_version = 0;
  std::int64_t last_count = 0;
  for (int i = 0; i < 8; ++i) {
    const std::string out = dir.file("snap-" + std::to_string(i) + ".db");
    const auto written = WriteSnapshot(source, out);
    ASSERT_TRUE(written.ok()) << written.error().message;
    Connection copy(out, {.create = false, .read_only = true});
    // A pincode, its key and its three offices are one transaction: a snapshot has all or none.
    const std::int64_t pincodes = copy.queryInt64("SELECT count(*) FROM pincodes");
    EXPECT_EQ(copy.queryInt64("SELECT count(*) FROM tag_keys"), pincodes);
    EXPECT_EQ(copy.queryInt64("SELECT count(*) FROM offices WHERE pincode >= 990000"),
              3 * (pincodes - seeded_pincodes));
    EXPECT_GE(written->registry_version, last_version);
    EXPECT_GE(pincodes, last_count);
    EXPECT_EQ(written->registry_version == last_version, pincodes == last_count);
    last_version = written->registry_version;
    last_count = pincodes;
  }
  stop = true;
  writer.join();
  EXPECT_GT(added.load(), 0);
}

TEST(Snapshot, AnUnwritableTargetIsAnErrorAndLeavesNothingBehind) {
  TempDir dir;
  Connection live = test::OpenExisting(test::CopyOfSeeded(dir));
  const auto missing_dir = WriteSnapshot(live, dir.file("no/such/dir/snapshot.db"));
  ASSERT_FALSE(missing_dir.ok());
  EXPECT_EQ(missing_dir.error().code, ErrorCode::kStorage);
  EXPECT_NE(missing_dir.error().message.find("no/such/dir"), std::string::npos)
      << missing_dir.error().message;

  // The target is a directory: refused before a copy is made, and nothing is left beside it.
  std::filesystem::create_directory(dir.file("taken"));
  const auto taken = WriteSnapshot(live, dir.file("taken"));
  ASSERT_FALSE(taken.ok());
  EXPECT_EQ(taken.error().code, ErrorCode::kStorage);
  for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
    EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos) << entry.path();
}

/// Overwrites 64 KiB a tenth of the way into `path` (16 pages of a seeded registry's tables and
/// indexes) with bytes no page holds, as a failing disk or a stray write would.
void DamagePagesPastTheFirst(const std::string& path) {
  const auto size = std::filesystem::file_size(path);
  ASSERT_GT(size, 8U << 20) << "a seeded registry";
  std::fstream in_place(path, std::ios::binary | std::ios::in | std::ios::out);
  in_place.seekp(static_cast<std::streamoff>(size / 10));
  in_place << std::string(64 << 10, '\xFF');
}

// The backup API copies pages as they are: a snapshot of a damaged database was written and
// reported as taken (exit 0), replicas then refused it, and as a backup it kept the damage.
TEST(Snapshot, OfADamagedDatabaseIsRefusedAndNothingIsWritten) {
  TempDir dir;
  const std::string damaged = test::CopyOfSeeded(dir);
  DamagePagesPastTheFirst(damaged);
  const std::string out = dir.file("snapshot.db");
  {
    Connection live = test::OpenExisting(damaged);
    const auto written = WriteSnapshot(live, out);
    ASSERT_FALSE(written.ok());
    EXPECT_EQ(written.error().code, ErrorCode::kStorage);
    const std::string& message = written.error().message;
    EXPECT_NE(message.find("the database " + damaged + " is damaged"), std::string::npos)
        << message;
    // A hundred findings, one per cell, filled a terminal: the first two and a count.
    EXPECT_NE(message.find(" more)"), std::string::npos) << message;
    EXPECT_LT(message.size(), 600U) << message;
  }
  EXPECT_FALSE(std::filesystem::exists(out));
  for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
    EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos) << entry.path();

  // A snapshot damaged after it was written is refused by --verify in the same few lines.
  const std::string sound = test::CopyOfSeeded(dir, "sound.db");
  {
    Connection live = test::OpenExisting(sound);
    ASSERT_TRUE(WriteSnapshot(live, out).ok());
  }
  DamagePagesPastTheFirst(out);
  const auto verified = VerifySnapshot(out);
  ASSERT_FALSE(verified.ok());
  EXPECT_EQ(verified.error().code, ErrorCode::kStorage);
  EXPECT_NE(verified.error().message.find("snapshot " + out + " is damaged: "), std::string::npos)
      << verified.error().message;
  EXPECT_LT(verified.error().message.size(), 600U) << verified.error().message;
}

// The copy reads the file at the source's path on a connection of its own. A review renamed a
// live database away and copied another file to its path: a snapshot then read the other file
// with the live one's write-ahead log, and closing checkpointed that log into it (the restore
// undone) and deleted the log under the live connections. Refused now, both files left alone.
TEST(Snapshot, OfADatabaseReplacedAtItsPathIsRefusedAndTouchesNeither) {
  TempDir dir;
  const std::string path = test::CopyOfSeeded(dir);
  const std::string restored = test::CopyOfSeeded(dir, "restored.db");
  Connection live = test::OpenExisting(path);
  live.execute("PRAGMA wal_autocheckpoint=0");  // the pincode below stays in the log
  ASSERT_TRUE(AddPincode(live, Pincode(999031), {TestOffice("Moved Nagar")}).ok());
  ASSERT_GT(std::filesystem::file_size(path + "-wal"), 0U);
  std::filesystem::rename(path, dir.file("moved-away.db"));
  std::filesystem::copy_file(restored, path);
  const std::string restored_bytes = test::ReadFile(path);

  const auto refused = WriteSnapshot(live, dir.file("snapshot.db"));
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, ErrorCode::kConflict);
  EXPECT_NE(refused.error().message.find("is no longer the database open here"), std::string::npos)
      << refused.error().message;
  EXPECT_FALSE(std::filesystem::exists(dir.file("snapshot.db")));
  EXPECT_EQ(test::ReadFile(path), restored_bytes);
  EXPECT_GT(std::filesystem::file_size(path + "-wal"), 0U);
  // The live connection still reads its own file, log and all.
  EXPECT_TRUE(LookupPincode(live, Pincode(999031)).ok());
}

TEST(Snapshot, NeverReplacesALiveDatabase) {
  TempDir dir;
  const std::string live_path = test::CopyOfSeeded(dir);
  Connection live = test::OpenExisting(live_path);
  const std::string keys_before = KeysCsv(live);

  // Its own source, by the same name and through another path to the same file.
  const std::string by_another_path =
      (dir.path() / "." / std::filesystem::path(live_path).filename()).string();
  for (const std::string& out : {live_path, by_another_path}) {
    const auto refused = WriteSnapshot(live, out);
    ASSERT_FALSE(refused.ok()) << out;
    EXPECT_EQ(refused.error().code, ErrorCode::kConflict);
    EXPECT_NE(refused.error().message.find("would replace the database"), std::string::npos)
        << refused.error().message;
  }
  // Another database a server has open (its write-ahead log beside it).
  const std::string other_path = test::CopyOfSeeded(dir, "other.db");
  Connection other = test::OpenExisting(other_path);
  ASSERT_TRUE(std::filesystem::exists(other_path + "-wal"));
  const auto other_refused = WriteSnapshot(live, other_path);
  ASSERT_FALSE(other_refused.ok());
  EXPECT_EQ(other_refused.error().code, ErrorCode::kConflict);
  // Nor the files SQLite keeps beside a database: a snapshot renamed over the source's write-ahead
  // log corrupted it (its committed pages were read from the snapshot), and so for the others'.
  AddPincode(live, Pincode(999003), {TestOffice("In The Log")}).value();
  ASSERT_TRUE(WriteSnapshot(live, dir.file("whole.db")).ok());
  const std::string whole = test::ReadFile(dir.file("whole.db"));
  for (const std::string& out :
       {live_path + "-wal", live_path + "-shm", live_path + "-journal", other_path + "-wal",
        (dir.path() / "." / (std::filesystem::path(live_path).filename().string() + "-wal"))
            .string()}) {
    const auto refused = WriteSnapshot(live, out);
    ASSERT_FALSE(refused.ok()) << out;
    EXPECT_EQ(refused.error().code, ErrorCode::kConflict) << out;
    EXPECT_NE(refused.error().message.find("would replace a file of the database"),
              std::string::npos)
        << refused.error().message;
    // A whole snapshot received for that path is refused for the same reason, nothing written.
    const bool existed = std::filesystem::exists(out);
    const std::string before = existed ? test::ReadFile(out) : std::string();
    const auto install = InstallSnapshot(whole, out);
    ASSERT_FALSE(install.ok()) << out;
    EXPECT_EQ(install.error().code, ErrorCode::kConflict) << out;
    EXPECT_NE(install.error().message.find("is a file of the database"), std::string::npos)
        << install.error().message;
    EXPECT_EQ(std::filesystem::exists(out), existed) << out;
    if (out.ends_with("-wal")) {
      EXPECT_EQ(test::ReadFile(out), before) << out;
    }
  }
  // Beside a file that is no database, such names are paths like any other.
  test::WriteFile(dir.path() / "notes", "not a database");
  EXPECT_TRUE(WriteSnapshot(live, dir.file("notes-wal")).ok());
  EXPECT_TRUE(LookupPincode(live, Pincode(999003)).ok());
  EXPECT_TRUE(WriteSnapshot(live, dir.file("snapshot-wal-free.db")).ok());

  // Both still whole and unchanged, and still writable.
  for (Connection* c : {&live, &other}) {
    Statement check = c->prepare("PRAGMA integrity_check");
    ASSERT_TRUE(check.step());
    EXPECT_EQ(check.getText(0), "ok");
    if (c == &other) {
      EXPECT_EQ(KeysCsv(*c), keys_before);
    }
  }
  EXPECT_TRUE(AddPincode(live, Pincode(999001), {TestOffice("After Refusal")}).ok());
  for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
    EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos) << entry.path();
}

TEST(Snapshot, VerifyRefusesWhatIsNotAWholeSnapshot) {
  TempDir dir;
  EXPECT_EQ(VerifySnapshot(dir.file("missing.db")).error().code, ErrorCode::kNotFound);
  const std::string junk = test::WriteFile(dir.file("junk.db"), std::string(8192, 'x'));
  EXPECT_EQ(VerifySnapshot(junk).error().code, ErrorCode::kStorage);

  Connection live = test::OpenExisting(test::CopyOfSeeded(dir));
  const std::string out = dir.file("snapshot.db");
  ASSERT_TRUE(WriteSnapshot(live, out).ok());
  // Cut in half, as a copy interrupted mid-transfer would be.
  const std::string whole = test::ReadFile(out);
  const std::string cut = test::WriteFile(dir.file("cut.db"), whole.substr(0, whole.size() / 2));
  const auto verified = VerifySnapshot(cut);
  ASSERT_FALSE(verified.ok());
  EXPECT_EQ(verified.error().code, ErrorCode::kStorage) << verified.error().message;
}

TEST(Snapshot, CommandLineWritesVerifiesAndRefusesAMissingSourceOrItself) {
  if (test::PintagExe().empty()) GTEST_SKIP() << "no pintag executable in this build";
  TempDir dir;
  const std::string live = test::CopyOfSeeded(dir);
  const std::string out = dir.file("published.db");
  const auto made =
      test::RunCommand(test::PintagExe() + " snapshot --db " + live + " --out " + out);
  ASSERT_EQ(made.exit_code, 0) << made.out;
  std::int64_t expected = 0;
  {
    Connection connection = test::OpenExisting(live);
    expected = VersionOf(connection);
  }
  EXPECT_NE(made.out.find("registry version " + std::to_string(expected)), std::string::npos)
      << made.out;
  const auto verified = test::RunCommand(test::PintagExe() + " snapshot --verify " + out);
  EXPECT_EQ(verified.exit_code, 0);
  EXPECT_EQ(verified.out, made.out);

  const std::string missing = dir.file("missing.db");
  const auto refused = test::RunCommand(test::PintagExe() + " snapshot --db " + missing +
                                        " --out " + dir.file("x.db") + " 2>&1");
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.out.find("does not exist"), std::string::npos) << refused.out;
  EXPECT_FALSE(std::filesystem::exists(missing));  // never created and seeded
  EXPECT_FALSE(std::filesystem::exists(dir.file("x.db")));

  // An empty file is not a registry to publish, and taking a snapshot never writes its source
  // (it once seeded an empty file with the bundled registry and published that).
  const std::string empty = test::WriteFile(dir.file("empty.db"), "");
  const auto of_empty = test::RunCommand(test::PintagExe() + " snapshot --db " + empty + " --out " +
                                         dir.file("y.db") + " 2>&1");
  EXPECT_EQ(of_empty.exit_code, 1);
  EXPECT_NE(of_empty.out.find("is empty: not a PinTag database"), std::string::npos)
      << of_empty.out;
  EXPECT_EQ(std::filesystem::file_size(empty), 0U);
  EXPECT_FALSE(std::filesystem::exists(dir.file("y.db")));

  const auto over_itself =
      test::RunCommand(test::PintagExe() + " snapshot --db " + live + " --out " + live + " 2>&1");
  EXPECT_EQ(over_itself.exit_code, 1);
  EXPECT_NE(over_itself.out.find("would replace the database it is taken from"), std::string::npos)
      << over_itself.out;
}

TEST(Snapshot, CommandLineInterruptedLeavesNoTemporaryFileBehind) {
  if (test::PintagExe().empty()) GTEST_SKIP() << "no pintag executable in this build";
  TempDir dir;
  const std::string live = test::CopyOfSeeded(dir);
  {
    // About 100 MB of scan log, which the snapshot copies, then deletes and vacuums away: the
    // temporary file exists for long enough to be interrupted.
    Connection connection = test::OpenExisting(live);
    connection.execute(
        "WITH RECURSIVE n(i) AS (SELECT 1 UNION ALL SELECT i + 1 FROM n WHERE i < 200000) "
        "INSERT INTO scan_log (scanned_at, image_bytes, result_json) "
        "SELECT '2026-12-05T00:00:00Z', 1, '\"' || hex(randomblob(250)) || '\"' FROM n");
  }
  const std::string out = dir.file("published.db");
  const auto temporaries = [&] {
    std::vector<std::string> found;
    for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
      const std::string name = entry.path().filename().string();
      if (name.rfind("published.db", 0) == 0) found.push_back(name);
    }
    return found;
  };
  const auto spawn = [&] {
    const std::string exe = test::PintagExe();
    std::vector<std::string> args = {exe, "snapshot", "--db", live, "--out", out};
    std::vector<char*> argv;
    argv.reserve(args.size() + 1);
    for (std::string& arg : args) argv.push_back(arg.data());
    argv.push_back(nullptr);
    pid_t pid = 0;
    return ::posix_spawn(&pid, exe.c_str(), nullptr, nullptr, argv.data(), environ) == 0 ? pid : -1;
  };
  // True once the temporary copy exists (polled every millisecond); false if the snapshot ended
  // first (its status in `status`).
  const auto copyingOrDone = [&](pid_t pid, int& status) {
    while (::waitpid(pid, &status, WNOHANG) == 0) {
      if (!temporaries().empty()) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    return false;
  };
  for (const int signal : {SIGINT, SIGTERM}) {
    const pid_t pid = spawn();
    ASSERT_GT(pid, 0);
    int status = 0;
    ASSERT_TRUE(copyingOrDone(pid, status))
        << "the snapshot ended before its temporary file was seen";
    ::kill(pid, signal);
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    ASSERT_TRUE(WIFSIGNALED(status)) << "the snapshot finished before the signal ended it: exit "
                                     << (WIFEXITED(status) ? WEXITSTATUS(status) : -1);
    EXPECT_EQ(WTERMSIG(status), signal);  // ended as the signal ends it, for the shell to see
    EXPECT_TRUE(temporaries().empty()) << temporaries().front() << " is left behind";
  }
  // Started with SIGHUP ignored, as under nohup: the signal changes nothing and the snapshot is
  // published.
  struct sigaction ignore {};
  ignore.sa_handler = SIG_IGN;
  ::sigemptyset(&ignore.sa_mask);
  struct sigaction before {};
  ASSERT_EQ(::sigaction(SIGHUP, &ignore, &before), 0);
  const pid_t pid = spawn();
  ::sigaction(SIGHUP, &before, nullptr);
  ASSERT_GT(pid, 0);
  int status = 0;
  ASSERT_TRUE(copyingOrDone(pid, status));
  ::kill(pid, SIGHUP);
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status)) << "ended by signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_TRUE(std::filesystem::exists(out));
  EXPECT_EQ(temporaries(), std::vector<std::string>{"published.db"});
}

// SIGKILL (or a power cut) leaves a writer's temporary file behind, about the registry's size.
// The next snapshot or install to the same target removes it, and only it: not a temporary file
// another writer holds, nor a file that only looks alike.
TEST(Snapshot, TemporaryFilesOfAKilledWriterAreRemovedByTheNext) {
  if (test::PintagExe().empty()) GTEST_SKIP() << "no pintag executable in this build";
  TempDir dir;
  const std::string live = test::CopyOfSeeded(dir);
  const std::string out = dir.file("published.db");
  const auto temporaries = [&] {
    std::vector<std::string> found;
    for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
      const std::string name = entry.path().filename().string();
      // The files themselves, not SQLite's -journal beside one.
      if (name.rfind("published.db.tmp-", 0) == 0 && name.find('-', 17) == std::string::npos) {
        found.push_back(name);
      }
    }
    std::sort(found.begin(), found.end());
    return found;
  };
  // A real `pintag snapshot` killed while it copies.
  const std::string exe = test::PintagExe();
  std::vector<std::string> args = {exe, "snapshot", "--db", live, "--out", out};
  std::vector<char*> argv;
  argv.reserve(args.size() + 1);
  for (std::string& arg : args) argv.push_back(arg.data());
  argv.push_back(nullptr);
  // Tried again when a copy ends before it is seen (one takes tens of milliseconds here).
  for (int attempt = 0; attempt < 5 && temporaries().empty(); ++attempt) {
    pid_t pid = 0;
    ASSERT_EQ(::posix_spawn(&pid, exe.c_str(), nullptr, nullptr, argv.data(), environ), 0);
    int status = 0;
    while (temporaries().empty() && ::waitpid(pid, &status, WNOHANG) == 0) {
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    ::kill(pid, SIGKILL);
    ::waitpid(pid, &status, 0);
  }
  const std::vector<std::string> killed = temporaries();
  ASSERT_EQ(killed.size(), 1U) << "no snapshot could be killed while copying";

  // A writer at work (its flock held) and two files that are not temporary files of `out`.
  const std::string held = dir.file("published.db.tmp-HeLd01");
  test::WriteFile(held, "being written");
  const int held_fd = ::open(held.c_str(), O_RDONLY | O_CLOEXEC);
  ASSERT_GE(held_fd, 0);
  ASSERT_EQ(::flock(held_fd, LOCK_EX | LOCK_NB), 0);
  const std::string short_name = test::WriteFile(dir.file("published.db.tmp-abc"), "mine");
  // A FIFO of a temporary file's name: opened to look at it, it blocked the sweep for good.
  ASSERT_EQ(::mkfifo(dir.file("published.db.tmp-fifo01").c_str(), 0600), 0);
  const std::string other_target = test::WriteFile(dir.file("other.db.tmp-abc123"), "mine");

  Connection source = test::OpenExisting(live);
  const auto written = WriteSnapshot(source, out);
  ASSERT_TRUE(written.ok()) << written.error().message;
  EXPECT_EQ(temporaries(),
            (std::vector<std::string>{"published.db.tmp-HeLd01", "published.db.tmp-abc",
                                      "published.db.tmp-fifo01"}));
  for (const char* side : {"-journal", "-wal", "-shm"}) {
    EXPECT_FALSE(std::filesystem::exists(dir.file(killed.front() + side))) << side;
  }
  EXPECT_TRUE(std::filesystem::exists(other_target));

  // Once its writer is gone, the held file goes too, here by an install.
  ::close(held_fd);
  const std::string bytes = test::ReadFile(out);
  ASSERT_TRUE(InstallSnapshot(bytes, out).ok());
  EXPECT_EQ(temporaries(),
            (std::vector<std::string>{"published.db.tmp-abc", "published.db.tmp-fifo01"}));
  EXPECT_EQ(test::ReadFile(short_name), "mine");
}

TEST(Snapshot, InstallPutsReceivedBytesInPlaceOnlyWhenTheyAreWhole) {
  TempDir dir;
  Connection live = test::OpenExisting(test::CopyOfSeeded(dir));
  const std::string published = dir.file("published.db");
  const auto written = WriteSnapshot(live, published);
  ASSERT_TRUE(written.ok()) << written.error().message;
  const std::string bytes = test::ReadFile(published);

  const std::string target = dir.file("replica.db");
  const auto installed = InstallSnapshot(bytes, target);
  ASSERT_TRUE(installed.ok()) << installed.error().message;
  EXPECT_EQ(installed->path, target);
  EXPECT_EQ(installed->registry_version, written->registry_version);
  EXPECT_EQ(test::ReadFile(target), bytes);

  // A truncated download and garbage are refused; the installed snapshot stays.
  const auto truncated = InstallSnapshot(std::string_view(bytes).substr(0, 100000), target);
  ASSERT_FALSE(truncated.ok());
  EXPECT_EQ(truncated.error().code, ErrorCode::kStorage) << truncated.error().message;
  EXPECT_FALSE(InstallSnapshot("<html>502 Bad Gateway</html>", target).ok());
  EXPECT_EQ(test::ReadFile(target), bytes);
  for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
    EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos) << entry.path();
}

// A primary restored from an older backup gives the keys it lost to the next pincodes it adds. A
// replica that took its registry would read every label printed with such a key as another
// pincode, so the snapshot the replica serves stays until one keeps all its keys.
TEST(Snapshot, InstallRefusesASnapshotThatDoesNotKeepTheServedKeys) {
  TempDir dir;
  const std::string primary_path = test::CopyOfSeeded(dir);
  const std::string backup_path = dir.file("backup.db");
  std::filesystem::copy_file(primary_path, backup_path);
  const auto snapshot_of = [&](Connection& connection, const std::string& name) {
    const auto written = WriteSnapshot(connection, dir.file(name));
    EXPECT_TRUE(written.ok()) << written.error().message;
    return test::ReadFile(dir.file(name));
  };
  const std::string target = dir.file("replica.db");
  Connection primary = test::OpenExisting(primary_path);
  const auto lost = AddPincode(primary, Pincode(100016), {TestOffice("Lost Nagar")});
  ASSERT_TRUE(lost.ok()) << lost.error().message;
  ASSERT_TRUE(InstallSnapshot(snapshot_of(primary, "before.db"), target).ok());
  const std::string served = test::ReadFile(target);
  const std::string lost_key = "key " + std::to_string(lost->key.value()) + " (pincode 100016)";

  // The backup, restored, lacks the key; then it gives it to the next pincode that probes there.
  Connection restored = test::OpenExisting(backup_path);
  const std::string without_key = snapshot_of(restored, "restored.db");
  const auto reused = AddPincode(restored, Pincode(101003), {TestOffice("Other Nagar")});
  ASSERT_TRUE(reused.ok()) << reused.error().message;
  ASSERT_EQ(reused->key.value(), lost->key.value()) << "101003 no longer probes to 100016's key";
  const std::string with_key_reused = snapshot_of(restored, "reused.db");
  for (const auto& [bytes, says] : {std::pair{without_key, lost_key + " is missing"},
                                    std::pair{with_key_reused, lost_key + " is given to 101003"}}) {
    const auto refused = InstallSnapshot(bytes, target);
    ASSERT_FALSE(refused.ok()) << says;
    EXPECT_EQ(refused.error().code, ErrorCode::kConflict);
    EXPECT_NE(refused.error().message.find(says), std::string::npos) << refused.error().message;
    EXPECT_EQ(test::ReadFile(target), served);
  }

  // The primary that kept its keys goes on replacing the snapshot as it changes.
  ASSERT_TRUE(AddPincode(primary, Pincode(999004), {TestOffice("Later Nagar")}).ok());
  const auto newer = InstallSnapshot(snapshot_of(primary, "after.db"), target);
  ASSERT_TRUE(newer.ok()) << newer.error().message;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
    EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos) << entry.path();
}

// A replica upgraded to a newer pintag holds its last snapshot of the older schema, which
// VerifySnapshot refuses as another version; the next snapshot must keep its keys all the same.
TEST(Snapshot, InstallComparesKeysWithAServedSnapshotOfAnOlderSchema) {
  TempDir dir;
  const std::string primary_path = test::CopyOfSeeded(dir);
  const std::string backup_path = dir.file("backup.db");
  std::filesystem::copy_file(primary_path, backup_path);
  Connection primary = test::OpenExisting(primary_path);
  const auto lost = AddPincode(primary, Pincode(100016), {TestOffice("Lost Nagar")});
  ASSERT_TRUE(lost.ok()) << lost.error().message;
  const std::string target = dir.file("replica.db");
  ASSERT_TRUE(WriteSnapshot(primary, target).ok());
  {
    Connection served(target, {.wal = false});
    served.execute("PRAGMA user_version = " + std::to_string(kSchemaVersion - 1));
  }
  ASSERT_FALSE(VerifySnapshot(target).ok());  // another schema version
  const std::string served = test::ReadFile(target);

  Connection restored = test::OpenExisting(backup_path);
  ASSERT_TRUE(WriteSnapshot(restored, dir.file("restored.db")).ok());
  const auto refused = InstallSnapshot(test::ReadFile(dir.file("restored.db")), target);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, ErrorCode::kConflict);
  EXPECT_NE(refused.error().message.find("key " + std::to_string(lost->key.value()) +
                                         " (pincode 100016) is missing"),
            std::string::npos)
      << refused.error().message;
  EXPECT_EQ(test::ReadFile(target), served);

  // The primary's own next snapshot, which keeps the keys, replaces it.
  ASSERT_TRUE(WriteSnapshot(primary, dir.file("after.db")).ok());
  const auto newer = InstallSnapshot(test::ReadFile(dir.file("after.db")), target);
  EXPECT_TRUE(newer.ok()) << newer.error().message;
}

// A registry a server writes is never replaced by a received snapshot, open (its log beside it)
// or closed (in WAL mode, which no snapshot is): renamed over an open one, its log corrupted the
// new file at the next checkpoint.
TEST(Snapshot, InstallNeverReplacesALiveRegistry) {
  TempDir dir;
  const std::string live_path = test::CopyOfSeeded(dir);
  std::string bytes;
  {
    Connection live = test::OpenExisting(live_path);
    const std::string published = dir.file("published.db");
    ASSERT_TRUE(WriteSnapshot(live, published).ok());
    bytes = test::ReadFile(published);
    ASSERT_TRUE(std::filesystem::exists(live_path + "-wal"));
    const auto refused = InstallSnapshot(bytes, live_path);
    ASSERT_FALSE(refused.ok());
    EXPECT_EQ(refused.error().code, ErrorCode::kConflict);
    EXPECT_NE(refused.error().message.find("is a live database"), std::string::npos)
        << refused.error().message;
    EXPECT_TRUE(AddPincode(live, Pincode(999002), {TestOffice("Still Written")}).ok());
  }
  ASSERT_FALSE(std::filesystem::exists(live_path + "-wal"));
  const std::string closed = test::ReadFile(live_path);
  for (const auto& refused : {InstallSnapshot(bytes, live_path), VerifySnapshot(live_path)}) {
    ASSERT_FALSE(refused.ok());
    EXPECT_EQ(refused.error().code, ErrorCode::kConflict);
    EXPECT_NE(refused.error().message.find("WAL mode"), std::string::npos)
        << refused.error().message;
  }
  EXPECT_EQ(test::ReadFile(live_path), closed);
  Connection live = test::OpenExisting(live_path);
  EXPECT_TRUE(LookupPincode(live, Pincode(999002)).ok());
  for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
    EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos) << entry.path();
}

// What a follower logs for a refused download names its target, not the random temporary file,
// so that the same refusal is logged once, not once a poll.
TEST(Snapshot, InstallRefusalsNameTheTargetNotTheTemporaryFile) {
  TempDir dir;
  const std::string target = dir.file("replica.db");
  std::string first;
  for (int i = 0; i < 2; ++i) {
    const auto refused = InstallSnapshot(std::string(8192, 'x'), target);
    ASSERT_FALSE(refused.ok());
    EXPECT_EQ(refused.error().message.find(".tmp-"), std::string::npos) << refused.error().message;
    EXPECT_NE(refused.error().message.find(target), std::string::npos) << refused.error().message;
    if (i == 0) {
      first = refused.error().message;
    } else {
      EXPECT_EQ(refused.error().message, first);
    }
  }
}

// Snapshot files are created as SQLite creates a database, 0644 less the umask: mkstemp's 0600
// kept a --read-only replica running as another user from serving them.
TEST(Snapshot, FilesAreReadableAsTheUmaskAllows) {
  TempDir dir;
  Connection live = test::OpenExisting(test::CopyOfSeeded(dir));
  const std::string bytes = [&] {
    const std::string published = dir.file("published.db");
    EXPECT_TRUE(WriteSnapshot(live, published).ok());
    return test::ReadFile(published);
  }();
  const auto mode_of = [](const std::string& path) {
    struct stat st {};
    EXPECT_EQ(::stat(path.c_str(), &st), 0) << path;
    return st.st_mode & 0777;
  };
  const mode_t previous = ::umask(022);
  ASSERT_TRUE(WriteSnapshot(live, dir.file("open.db")).ok());
  ASSERT_TRUE(InstallSnapshot(bytes, dir.file("installed.db")).ok());
  ::umask(077);
  ASSERT_TRUE(WriteSnapshot(live, dir.file("private.db")).ok());
  ::umask(previous);
  EXPECT_EQ(mode_of(dir.file("open.db")), 0644U);
  EXPECT_EQ(mode_of(dir.file("installed.db")), 0644U);
  EXPECT_EQ(mode_of(dir.file("private.db")), 0600U);
}

TEST(ScanLogFile, AReplicaAppendsToItsOwnFile) {
  TempDir dir;
  auto log = OpenScanLogFile(dir.file("scans.db"));
  ASSERT_TRUE(log.ok()) << log.error().message;
  Connection& connection = log.value();
  ASSERT_TRUE(AppendScan(connection, {.token_id = 7, .image_bytes = 5, .result_json = "[]"}).ok());
  ASSERT_FALSE(AppendScan(connection, {.image_bytes = 5, .result_json = "{not json"}).ok());
  const auto scans = RecentScans(connection, 10);
  ASSERT_TRUE(scans.ok()) << scans.error().message;
  ASSERT_EQ(scans->size(), 1u);
  EXPECT_EQ(scans->at(0).token_id, 7);
  // Reopening keeps what was logged.
  auto again = OpenScanLogFile(dir.file("scans.db"));
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(RecentScans(again.value(), 10).value().size(), 1u);
  // SQLite's own tables (ANALYZE's statistics) are not another program's: still a scan log.
  again.value().execute("ANALYZE");
  ASSERT_EQ(
      again.value().queryInt64("SELECT count(*) FROM sqlite_schema WHERE name = 'sqlite_stat1'"),
      1);
  auto analyzed = OpenScanLogFile(dir.file("scans.db"));
  ASSERT_TRUE(analyzed.ok()) << analyzed.error().message;
  // A table of anything else is: the file is left as it was.
  again.value().execute("CREATE TABLE pincodes (pincode INTEGER)");
  const auto refused = OpenScanLogFile(dir.file("scans.db"));
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, ErrorCode::kConflict);
  EXPECT_NE(refused.error().message.find("holds other tables (pincodes)"), std::string::npos)
      << refused.error().message;
}

}  // namespace
}  // namespace pintag::db
