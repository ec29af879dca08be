// The scan log: one row per decoded photo, appended alone or in batches.

#include <gtest/gtest.h>

#include <chrono>
#include <string>
#include <vector>

#include "db_test_util.hpp"
#include "pintag/db/scan_log.hpp"
#include "pintag/db/tokens.hpp"

namespace pintag::db {
namespace {

using test::TempDir;

class ScanLog : public ::testing::Test {
 protected:
  TempDir dir_;
  Connection db_ = test::OpenExisting(test::CopyOfSeeded(dir_));
};

TEST_F(ScanLog, AppendsAndListsNewestFirst) {
  const auto token = CreateToken(db_, Role::kScanner).value();
  ScanRecord scan{.token_id = token.info.id,
                  .image_bytes = 123456,
                  .image_width = 1920,
                  .image_height = 1080,
                  .result_json = R"({"tags":[{"pincode":"110001","key":11684}]})"};
  const auto first = AppendScan(db_, scan);
  ASSERT_TRUE(first.ok()) << first.error().message;
  scan.result_json = R"({"tags":[]})";
  scan.image_width.reset();
  ASSERT_TRUE(AppendScan(db_, scan).ok());
  ASSERT_TRUE(AppendScan(db_, {.image_bytes = 1, .result_json = "[]"}).ok());

  const auto recent = RecentScans(db_, 10).value();
  ASSERT_EQ(recent.size(), 3u);
  EXPECT_EQ(recent[0].result_json, "[]");
  EXPECT_FALSE(recent[0].token_id.has_value());
  EXPECT_EQ(recent[2].id, *first);
  EXPECT_EQ(recent[2].image_width, 1920);
  EXPECT_EQ(recent[2].result_json, R"({"tags":[{"pincode":"110001","key":11684}]})");
  EXPECT_FALSE(recent[2].scanned_at.empty());
  EXPECT_EQ(RecentScans(db_, 10, token.info.id).value().size(), 2u);
  EXPECT_EQ(RecentScans(db_, 1).value().size(), 1u);

  EXPECT_EQ(AppendScan(db_, {.result_json = "{not json"}).error().code, ErrorCode::kInvalid);
  EXPECT_EQ(AppendScan(db_, {.token_id = 999, .result_json = "{}"}).error().code,
            ErrorCode::kInvalid);
  EXPECT_EQ(RecentScans(db_, 0).error().code, ErrorCode::kInvalid);
}

TEST_F(ScanLog, ScanTimeWritesUtcWithMilliseconds) {
  using std::chrono::milliseconds;
  // 2026-12-06 16:20:01.007 UTC, counted from the epoch by hand: 20,793 days and 58,801 s.
  const std::chrono::system_clock::time_point when{
      milliseconds(20'793LL * 86'400'000 + 58'801'000 + 7)};
  EXPECT_EQ(ScanTime(when), "2026-12-06T16:20:01.007Z");
}

TEST_F(ScanLog, ABatchIsWrittenInOrderWithTheTimesItWasGiven) {
  const auto token = CreateToken(db_, Role::kScanner).value();
  const std::vector<ScanRecord> batch = {
      {.scanned_at = "2026-12-06T10:00:00.001Z", .token_id = token.info.id, .result_json = "[1]"},
      {.image_bytes = 5, .result_json = "[2]"},
      {.scanned_at = "2026-12-06T10:00:00.003Z", .image_bytes = 7, .result_json = "[3]"},
  };
  const auto appended = AppendScans(db_, batch);
  ASSERT_TRUE(appended.ok()) << appended.error().message;
  EXPECT_EQ(appended->written, 3u);
  EXPECT_TRUE(appended->refused.empty());

  const auto recent = RecentScans(db_, 10).value();
  ASSERT_EQ(recent.size(), 3u);
  EXPECT_EQ(recent[2].result_json, "[1]");
  EXPECT_EQ(recent[2].scanned_at, "2026-12-06T10:00:00.001Z");
  EXPECT_EQ(recent[2].token_id, token.info.id);
  EXPECT_EQ(recent[1].result_json, "[2]");
  EXPECT_EQ(recent[1].scanned_at.size(), std::string("2026-12-06T10:00:00.001Z").size())
      << "no time given: the time of the append, in the same form";
  EXPECT_EQ(recent[0].scanned_at, "2026-12-06T10:00:00.003Z");
  EXPECT_LT(recent[2].id, recent[1].id);
  EXPECT_LT(recent[1].id, recent[0].id);
}

TEST_F(ScanLog, ABadScanInABatchIsLeftOutAndTheRestWritten) {
  const std::vector<ScanRecord> batch = {
      {.result_json = "[1]"},
      {.result_json = "{not json"},
      {.token_id = 999'999, .result_json = "[3]"},
      {.scanned_at = "yesterday", .result_json = "[4]"},
      {.result_json = "[5]"},
  };
  const auto appended = AppendScans(db_, batch);
  ASSERT_TRUE(appended.ok()) << appended.error().message;
  EXPECT_EQ(appended->written, 2u);
  ASSERT_EQ(appended->refused.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(appended->refused[i].index, i + 1);
    EXPECT_EQ(appended->refused[i].error.code, ErrorCode::kInvalid);
  }
  const auto recent = RecentScans(db_, 10).value();
  ASSERT_EQ(recent.size(), 2u);
  EXPECT_EQ(recent[0].result_json, "[5]");
  EXPECT_EQ(recent[1].result_json, "[1]");
  EXPECT_EQ(
      AppendScan(db_, {.scanned_at = "2026-12-06 10:00:00", .result_json = "[]"}).error().code,
      ErrorCode::kInvalid);
}

TEST_F(ScanLog, ABatchThatCannotTakeTheLockWritesNothingAndSaysBusy) {
  Connection other = test::OpenExisting(db_.path());
  Transaction holding(other);  // BEGIN IMMEDIATE: the write lock, as another process's import
  Connection impatient(db_.path(), {.create = false, .busy_timeout_ms = 50});
  const std::vector<ScanRecord> batch = {{.result_json = "[1]"}, {.result_json = "[2]"}};
  const auto appended = AppendScans(impatient, batch);
  ASSERT_FALSE(appended.ok());
  EXPECT_EQ(appended.error().code, ErrorCode::kBusy);
  holding.commit();
  EXPECT_TRUE(RecentScans(db_, 10).value().empty());
}

// A hub's scan log grows by every scan; pruning takes the old ones away in batches, in time
// order, and leaves the rest (and scans whose time is later than a newer neighbour's) alone.
TEST_F(ScanLog, PruneRemovesScansTakenBeforeACutoffInBatches) {
  // Times mostly ascending by id, as a server writes them, with one written out of order.
  const std::vector<std::string> times = {"2026-01-01T00:00:00.000Z", "2026-01-15T12:00:00.000Z",
                                          "2026-03-01T00:00:00.000Z", "2026-01-20T08:00:00.000Z",
                                          "2026-02-28T23:59:59.999Z", "2026-06-01T00:00:00.000Z",
                                          "2026-02-01T00:00:00.000Z"};
  for (const std::string& time : times) {
    ASSERT_TRUE(AppendScan(db_, {.scanned_at = time, .result_json = "{}"}).ok()) << time;
  }
  // Batches of two: several transactions, the last partly empty.
  const auto removed = PruneScans(db_, "2026-03-01", 2);
  ASSERT_TRUE(removed.ok()) << removed.error().message;
  EXPECT_EQ(*removed, 5U);
  const std::vector<ScanRecord> recent = RecentScans(db_, 100).value();
  std::vector<std::string> left;
  left.reserve(recent.size());
  for (const ScanRecord& scan : recent) left.push_back(scan.scanned_at);
  EXPECT_EQ(left,
            (std::vector<std::string>{"2026-06-01T00:00:00.000Z", "2026-03-01T00:00:00.000Z"}));
  // Nothing older is left: again removes none; a scan time as the cutoff is taken to the ms.
  EXPECT_EQ(PruneScans(db_, "2026-03-01").value(), 0U);
  EXPECT_EQ(PruneScans(db_, "2026-03-01T00:00:00.001Z").value(), 1U);
  EXPECT_EQ(RecentScans(db_, 100).value().size(), 1U);
  for (const char* bad : {"2026-3-1", "yesterday", "2026-03-01T00:00:00Z", ""}) {
    const auto refused = PruneScans(db_, bad);
    ASSERT_FALSE(refused.ok()) << bad;
    EXPECT_EQ(refused.error().code, ErrorCode::kInvalid) << bad;
  }
  EXPECT_EQ(PruneScans(db_, "2026-03-01", 0).error().code, ErrorCode::kInvalid);
  EXPECT_FALSE(db_.inTransaction());
}

}  // namespace
}  // namespace pintag::db
