// The per-connection prepared-statement cache: a reused statement starts clean (reset, no
// bindings, no read snapshot held), two live statements with the same SQL are independent, and
// a bad statement is never cached.

#include <gtest/gtest.h>

#include <vector>

#include "db_test_util.hpp"
#include "pintag/db/sqlite.hpp"

namespace pintag::db {
namespace {

using test::TempDir;

class StatementCacheTest : public ::testing::Test {
 protected:
  StatementCacheTest() : path_(dir_.file("cache.db")), connection_(path_) {
    connection_.execute("CREATE TABLE t (x INTEGER); INSERT INTO t VALUES (1), (2), (3);");
  }
  TempDir dir_;
  std::string path_;
  Connection connection_;
};

TEST_F(StatementCacheTest, AReusedStatementHasNoBindingsLeft) {
  constexpr const char* kSql = "SELECT count(*) FROM t WHERE x = ?1";
  {
    Statement first = connection_.prepare(kSql);
    first.bind(1, 2);
    ASSERT_TRUE(first.step());
    EXPECT_EQ(first.getInt64(0), 1);
  }
  Statement again = connection_.prepare(kSql);
  ASSERT_TRUE(again.step());
  EXPECT_EQ(again.getInt64(0), 0) << "x = NULL matches nothing; the old binding was kept";
}

TEST_F(StatementCacheTest, TwoLiveStatementsWithTheSameSqlStepIndependently) {
  constexpr const char* kSql = "SELECT x FROM t ORDER BY x";
  std::vector<std::pair<int, int>> pairs;
  Statement outer = connection_.prepare(kSql);
  while (outer.step()) {
    Statement inner = connection_.prepare(kSql);
    while (inner.step()) pairs.emplace_back(outer.getInt(0), inner.getInt(0));
  }
  EXPECT_EQ(pairs.size(), 9u);
  EXPECT_EQ(pairs.front(), std::make_pair(1, 1));
  EXPECT_EQ(pairs.back(), std::make_pair(3, 3));
}

TEST_F(StatementCacheTest, AStatementLeftMidwayHoldsNoSnapshotOnceItEnds) {
  constexpr const char* kSql = "SELECT x FROM t ORDER BY x";
  {
    Statement partial = connection_.prepare(kSql);
    ASSERT_TRUE(partial.step());  // a read transaction is open here, then the statement ends
  }
  Connection writer(path_);
  writer.execute("INSERT INTO t VALUES (4)");
  // Had the cached statement kept its read transaction, this would still see three rows.
  EXPECT_EQ(connection_.queryInt64("SELECT count(*) FROM t"), 4);
  Statement again = connection_.prepare(kSql);
  int rows = 0;
  while (again.step()) ++rows;
  EXPECT_EQ(rows, 4);
  // And the writer can checkpoint the whole WAL: no reader pins its old frames. A pinned WAL
  // does not make the pragma fail; it answers busy = 1 (its first column).
  Statement checkpoint = writer.prepare("PRAGMA wal_checkpoint(TRUNCATE)");
  ASSERT_TRUE(checkpoint.step());
  EXPECT_EQ(checkpoint.getInt64(0), 0) << "a reader still pins the WAL";
}

TEST_F(StatementCacheTest, BadSqlThrowsEveryTimeAndManyDistinctStatementsAllWork) {
  for (int attempt = 0; attempt < 2; ++attempt) {
    EXPECT_THROW(connection_.prepare("SELECT nope FROM t"), SqliteError);
    EXPECT_THROW(connection_.prepare(" -- only a comment"), SqliteError);
  }
  // More distinct statements than the cache keeps: the ones past its bound are compiled per use.
  for (int round = 0; round < 2; ++round) {
    for (int i = 0; i < 100; ++i) {
      Statement s = connection_.prepare("SELECT count(*) + " + std::to_string(i) + " FROM t");
      ASSERT_TRUE(s.step());
      EXPECT_EQ(s.getInt64(0), 3 + i);
    }
  }
}

TEST_F(StatementCacheTest, ACachedStatementSeesASchemaChange) {
  {
    Statement before = connection_.prepare("SELECT * FROM t");
    ASSERT_TRUE(before.step());
  }
  connection_.execute("ALTER TABLE t ADD COLUMN y INTEGER DEFAULT 7");
  Statement after = connection_.prepare("SELECT * FROM t");
  ASSERT_TRUE(after.step());
  EXPECT_EQ(after.getInt64(1), 7);
}

}  // namespace
}  // namespace pintag::db
