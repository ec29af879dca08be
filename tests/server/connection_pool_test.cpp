// The connection pool of a read-only replica while its snapshot is swapped under it, the way
// SnapshotWatcher does: the new file is handed to renew() and the previous file's name removed
// at once. A lease taken at any moment of that must open a file that is there. And a primary's
// pool when its file is replaced under it: it must stop writing, and leave no log behind that
// the new file would take as its own.

#include "app/connection_pool.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "pintag/db/sqlite.hpp"
#include "pintag/server/problem.hpp"
#include "pintag/test/files.hpp"

namespace pintag::app {
namespace {

TEST(ConnectionPool, LeasesTakenWhileTheFileIsSwappedAndUnlinkedAllOpen) {
  const test::TempDir dir;
  const std::string original = dir.file("registry.db");
  {
    db::Connection create(original);
    create.execute("CREATE TABLE t (x INTEGER); INSERT INTO t VALUES (7);");
    create.execute("PRAGMA journal_mode=DELETE");  // a snapshot is one file, no WAL beside it
  }
  const auto serving = [&](int n) { return dir.file("registry.db.serving-" + std::to_string(n)); };
  ASSERT_EQ(::link(original.c_str(), serving(0).c_str()), 0);
  ConnectionPool pool(serving(0), 5000, /*read_only=*/true);

  constexpr int kThreads = 4;
  constexpr int kSwaps = 2000;
  std::atomic<bool> stop{false};
  std::atomic<int> refused{0}, wrong{0}, leases{0};
  std::vector<std::thread> threads;
  threads.reserve(kThreads);
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&] {
      while (!stop) {
        try {
          const ConnectionPool::Lease lease = pool.acquire();
          if (lease->queryInt64("SELECT x FROM t") != 7) ++wrong;
          ++leases;
        } catch (const server::HttpError&) {
          ++refused;
        }
      }
    });
  }
  // Each swap is what the watcher does: a new link to the file, renew, the old link removed.
  // Every swap waits for a lease after the one before (the deadline only keeps a broken pool
  // from hanging the test), so swaps and leases interleave however the threads are scheduled.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  for (int n = 1; n <= kSwaps; ++n) {
    if (::link(original.c_str(), serving(n).c_str()) != 0) {
      ADD_FAILURE() << "cannot link " << serving(n);
      break;  // the threads are stopped and joined below
    }
    pool.renew(serving(n));
    ::unlink(serving(n - 1).c_str());
    const int before = leases + refused;
    while (leases + refused < before + 1 && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::yield();
    }
  }
  stop = true;
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(refused.load(), 0) << "of " << leases.load() << " leases";
  EXPECT_EQ(wrong.load(), 0);
  EXPECT_GE(leases.load() + refused.load(), kSwaps) << "the deadline ran out";
}

std::int64_t Rows(const std::string& path) {
  db::ConnectionOptions options;
  options.create = false;
  db::Connection connection(path, options);
  db::Statement check = connection.prepare("PRAGMA integrity_check");
  EXPECT_TRUE(check.step());
  EXPECT_EQ(check.getText(0), "ok") << path;
  return connection.queryInt64("SELECT count(*) FROM t");
}

TEST(ConnectionPool, AFileReplacedUnderAWritablePoolIsNotWrittenAndLeavesNoLog) {
  const test::TempDir dir;
  const std::string served = dir.file("registry.db");
  const std::string backup = dir.file("backup.db");
  for (const std::string& path : {served, backup}) {
    db::Connection create(path);
    create.execute("CREATE TABLE t (x INTEGER)");
  }
  ConnectionPool pool(served);
  {
    const ConnectionPool::Lease lease = pool.acquire();
    for (int i = 0; i < 5; ++i) lease->execute("INSERT INTO t VALUES (1)");
  }
  ASSERT_GT(std::filesystem::file_size(served + "-wal"), 0U) << "the rows must be in the log";

  // An operator restores a backup by renaming it over the served file.
  std::filesystem::rename(served, dir.file("before-restore.db"));
  std::filesystem::rename(backup, served);
  try {
    const ConnectionPool::Lease lease = pool.acquire();
    ADD_FAILURE() << "a lease on a replaced file was given";
  } catch (const server::HttpError& e) {
    EXPECT_EQ(e.problem().status, 503);
    EXPECT_NE(e.problem().detail.find("replaced"), std::string::npos) << e.problem().detail;
  }
  EXPECT_FALSE(pool.servesFileAtPath());
  // The log at the path is empty, its rows in the file they were written to; the restored file
  // opens as it was restored.
  EXPECT_EQ(std::filesystem::file_size(served + "-wal"), 0U);
  EXPECT_EQ(Rows(dir.file("before-restore.db")), 5);
  EXPECT_EQ(Rows(served), 0);

  // Put back, the served file is served again.
  std::filesystem::rename(served, backup);
  std::filesystem::rename(dir.file("before-restore.db"), served);
  EXPECT_TRUE(pool.servesFileAtPath());
  const ConnectionPool::Lease lease = pool.acquire();
  lease->execute("INSERT INTO t VALUES (1)");
  EXPECT_EQ(lease->queryInt64("SELECT count(*) FROM t"), 6);
}

TEST(ConnectionPool, AMovedFilesLogIsEmptiedOnceReadersAndLeasesLetIt) {
  const test::TempDir dir;
  const std::string served = dir.file("registry.db");
  {
    db::Connection create(served);
    create.execute("CREATE TABLE t (x INTEGER)");
  }
  ConnectionPool pool(served);
  { (void)pool.acquire()->execute("INSERT INTO t VALUES (1)"); }

  // A reader elsewhere holds the log: the first try cannot empty it.
  auto reader = std::make_unique<db::Connection>(served);
  reader->execute("BEGIN");
  EXPECT_EQ(reader->queryInt64("SELECT count(*) FROM t"), 1);
  // A lease taken before the move writes after it.
  std::optional<ConnectionPool::Lease> late(pool.acquire());
  std::filesystem::rename(served, dir.file("moved.db"));
  EXPECT_FALSE(pool.servesFileAtPath());
  (*late)->execute("INSERT INTO t VALUES (2)");
  EXPECT_GT(std::filesystem::file_size(served + "-wal"), 0U);

  reader->execute("COMMIT");
  reader.reset();
  late.reset();  // its connection comes back while the file is away: the log is emptied now
  EXPECT_EQ(std::filesystem::file_size(served + "-wal"), 0U);
  EXPECT_EQ(Rows(dir.file("moved.db")), 2);
}

// A lease given back inside a transaction (a request that began one and whose COMMIT failed)
// must not hand the next request a connection that refuses BEGIN or reads an old state.
TEST(ConnectionPool, ALeaseGivenBackInsideATransactionIsRolledBack) {
  const test::TempDir dir;
  const std::string path = dir.file("registry.db");
  {
    db::Connection create(path);
    create.execute(
        "PRAGMA journal_mode=WAL; CREATE TABLE t (x INTEGER); INSERT INTO t VALUES (1);");
  }
  ConnectionPool pool(path, 5000, /*read_only=*/false);
  {
    const ConnectionPool::Lease lease = pool.acquire();
    lease->execute("BEGIN");
    EXPECT_EQ(lease->queryInt64("SELECT x FROM t"), 1);  // its reads now see this state
    ASSERT_TRUE(lease->inTransaction());
  }
  {
    db::Connection writer(path);
    writer.execute("UPDATE t SET x = 2");
  }
  const ConnectionPool::Lease next = pool.acquire();
  EXPECT_FALSE(next->inTransaction());
  EXPECT_EQ(next->queryInt64("SELECT x FROM t"), 2);
  const db::ReadTransaction read(*next);  // BEGIN, which an open transaction refuses
  EXPECT_EQ(next->queryInt64("SELECT x FROM t"), 2);
}

TEST(ConnectionPool, AReadOnlyPoolServesWhateverFileIsAtItsPath) {
  // A replica's file is replaced by design (SnapshotWatcher renews the pool after).
  const test::TempDir dir;
  const std::string served = dir.file("snapshot.db");
  for (const std::string& path : {served, dir.file("next.db")}) {
    db::Connection create(path);
    create.execute("CREATE TABLE t (x INTEGER); PRAGMA journal_mode=DELETE");
  }
  ConnectionPool pool(served, 5000, /*read_only=*/true);
  (void)pool.acquire();
  std::filesystem::rename(dir.file("next.db"), served);
  EXPECT_TRUE(pool.servesFileAtPath());
  EXPECT_EQ(pool.acquire()->queryInt64("SELECT count(*) FROM t"), 0);
}

}  // namespace
}  // namespace pintag::app
