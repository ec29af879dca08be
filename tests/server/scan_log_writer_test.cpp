// The scan log's writer when a connection to its file cannot be opened for a while: the process
// has run out of file descriptors (a burst of clients, each socket one descriptor). The scans
// answered meanwhile are held and written once a connection opens, not lost.

#include "app/scan_log_writer.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>
#include <memory>
#include <string>
#include <vector>

#include "app/connection_pool.hpp"
#include "pintag/db/scan_log.hpp"
#include "pintag/server/metrics.hpp"
#include "pintag/test/files.hpp"

namespace pintag::app {
namespace {

constexpr const char* kLostCounter = "pintag_scan_log_failures_total";

/// While it lives, the process can open no file: its descriptor limit is lowered and every
/// descriptor under it is taken.
class DescriptorsExhausted {
 public:
  DescriptorsExhausted() {
    ::getrlimit(RLIMIT_NOFILE, &before_);
    rlimit lowered = before_;
    lowered.rlim_cur = std::min<rlim_t>(before_.rlim_cur, 256);
    ::setrlimit(RLIMIT_NOFILE, &lowered);
    while (true) {
      const int fd = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
      if (fd < 0) {
        exhausted_ = errno == EMFILE;
        break;
      }
      taken_.push_back(fd);
    }
  }
  ~DescriptorsExhausted() {
    for (const int fd : taken_) ::close(fd);
    ::setrlimit(RLIMIT_NOFILE, &before_);
  }
  DescriptorsExhausted(const DescriptorsExhausted&) = delete;
  DescriptorsExhausted& operator=(const DescriptorsExhausted&) = delete;

  bool exhausted() const { return exhausted_; }

 private:
  rlimit before_{};
  std::vector<int> taken_;
  bool exhausted_ = false;
};

db::ScanRecord Scan(int n) {
  db::ScanRecord scan;
  scan.image_bytes = 1000 + n;
  scan.result_json = R"({"tags":[],"n":)" + std::to_string(n) + "}";
  return scan;
}

TEST(ScanLogWriter, ScansAnsweredWhileNoFileCanBeOpenedAreWrittenOnceOneCan) {
  const test::TempDir dir;
  const std::string path = dir.file("scans.db");
  ASSERT_TRUE(db::OpenScanLogFile(path));
  // A new pool holds no connection: the writer's first lease must open one.
  auto pool = std::make_shared<ConnectionPool>(path, 5000, /*read_only=*/false);
  auto metrics = std::make_shared<server::Metrics>();
  ScanLogWriter writer(pool, metrics, kLostCounter);
  {
    const DescriptorsExhausted exhausted;
    ASSERT_TRUE(exhausted.exhausted());
    // Each append waits up to kWaitForWrite for its row, then returns with the scan held.
    writer.append(Scan(1), "req-1");
    writer.append(Scan(2), "req-2");
  }
  writer.finish();  // the retry after kRetryPause finds descriptors again

  EXPECT_EQ(metrics->counter(kLostCounter), 0);
  auto opened = db::OpenScanLogFile(path);
  ASSERT_TRUE(opened);
  auto scans = db::RecentScans(opened.value(), 10);
  ASSERT_TRUE(scans);
  ASSERT_EQ(scans->size(), 2U);
  EXPECT_EQ(scans->at(1).image_bytes, 1001);  // newest first
  EXPECT_EQ(scans->at(0).image_bytes, 1002);
}

}  // namespace
}  // namespace pintag::app
