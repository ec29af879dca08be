// Readers on their own connections keep working, and see the last committed state, while a
// writer imports.

#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "db_test_util.hpp"
#include "pintag/db/importer.hpp"
#include "pintag/db/registry.hpp"
#include "pintag/db/sort_plan.hpp"

namespace pintag::db {
namespace {

using test::TempDir;

TEST(Concurrency, ReadersKeepWorkingWhileAWriterImports) {
  TempDir dir;
  const std::string path = test::CopyOfSeeded(dir);
  std::string csv =
      "officename,pincode,officeType,Deliverystatus,divisionname,regionname,circlename,Taluk,"
      "Districtname,statename\n";
  for (int p = 0; p < 3000; ++p) {
    csv += "Reader Test B.O," + std::to_string(900000 + p) + ",BO,Delivery,D,R,C,T,X,S\n";
  }

  std::mutex mutex;
  std::condition_variable changed;
  bool writer_inside = false;  // the writer holds its open transaction, rows written
  bool reader_done = false;
  Result<ImportReport> report = Error{ErrorCode::kStorage, "not run"};

  std::thread writer([&] {
    Connection connection = test::OpenExisting(path);
    ImportOptions options;
    options.progress = [&](std::string_view phase, std::uint64_t done, std::uint64_t) {
      if (phase != "write" || done < 2048) return;
      std::unique_lock lock(mutex);
      if (writer_inside) return;
      writer_inside = true;
      changed.notify_all();
      changed.wait(lock, [&] { return reader_done; });
    };
    report = ImportDirectoryCsv(connection, csv, options);
  });

  // The writer is let go and joined however the reads below end, failed assertions included.
  const auto release_writer = [&] {
    {
      std::lock_guard lock(mutex);
      reader_done = true;
    }
    changed.notify_all();
    writer.join();
  };
  Connection reader = test::OpenExisting(path);
  // No waiting on locks: a read that would block on the writer fails at once with SQLITE_BUSY.
  reader.execute("PRAGMA busy_timeout = 0");
  const auto read_while_writing = [&] {
    {
      std::unique_lock lock(mutex);
      ASSERT_TRUE(changed.wait_for(lock, std::chrono::seconds(60), [&] { return writer_inside; }));
    }
    // The writer is mid-transaction with 2,049 pincodes inserted but not committed.
    for (int i = 0; i < 50; ++i) {
      const auto record = LookupPincode(reader, Pincode(110001));
      ASSERT_TRUE(record.ok()) << record.error().message;
      const auto counts = CountRegistry(reader);
      ASSERT_TRUE(counts.ok()) << counts.error().message;
      EXPECT_EQ(counts->pincodes_active, 19159);  // the last committed state
      EXPECT_EQ(LookupPincode(reader, Pincode(900000)).error().code, ErrorCode::kNotFound);
      ASSERT_TRUE(Search(reader, {.name_prefix = "Reader", .limit = 5}).ok());
      ASSERT_TRUE(Route(reader, Pincode(560001), kDefaultPlanName).ok());
    }
  };
  read_while_writing();
  release_writer();
  ASSERT_TRUE(report.ok()) << report.error().message;
  EXPECT_EQ(report->pincodes_added.size(), 3000u);
  EXPECT_EQ(CountRegistry(reader).value().pincodes_active, 19159 + 3000);
}

}  // namespace
}  // namespace pintag::db
