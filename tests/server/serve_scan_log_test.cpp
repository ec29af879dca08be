// The scan log while another process holds the database's write lock (`pintag import` on the
// served file): scans are answered without waiting for it, held back, and written once it is
// released, with the time they were scanned; a server stopped meanwhile writes them before it
// exits.

#include <chrono>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <thread>
#include <vector>

#include "held_write_lock.hpp"
#include "pintag/codec/tag_raster.hpp"
#include "pintag/db/database.hpp"
#include "pintag/db/scan_log.hpp"
#include "pintag/db/text.hpp"
#include "serve_fixture.hpp"

namespace pintag::serve_test {
namespace {

using nlohmann::json;

/// A small photo without a tag: decoded, read (nothing found) and logged like any other.
std::string TaglessPng() {
  cv::Mat photo(48, 64, CV_8UC3);
  cv::randu(photo, cv::Scalar::all(0), cv::Scalar::all(255));
  std::vector<std::uint8_t> png;
  cv::imencode(".png", photo, png);
  return {png.begin(), png.end()};
}

/// The scans in the log at `path`, oldest first: as they are now, or once there are `expected` of
/// them (ScanRowsOnceThereAre's wait).
std::vector<db::ScanRecord> ScansOnceThereAre(const std::string& path, std::size_t expected,
                                              bool wait) {
  if (wait) ScanRowsOnceThereAre(path, static_cast<std::int64_t>(expected));
  std::vector<db::ScanRecord> scans;
  auto opened = db::OpenDatabase(path, {.create = false});
  if (opened) {
    auto recent = db::RecentScans(opened.value().connection, 1000);
    if (recent) scans.assign(recent->rbegin(), recent->rend());
  }
  return scans;
}

double ScrapedMetric(httplib::Client& client, const std::string& series) {
  const auto page = client.Get("/metrics");
  if (!page || page->status != 200) {
    ADD_FAILURE() << "GET /metrics failed";
    return -1;
  }
  return Metric(page->body, series);
}

TEST_F(ServeTest, ScansWhileAnotherProcessHoldsTheLockAreAnsweredAndLoggedOnceItIsReleased) {
  const std::string photo = TaglessPng();
  // Twice the fixture's 4 worker threads: were a scan to wait for the lock on its thread, the
  // last four would wait behind the first four.
  constexpr int kScans = 8;
  HeldWriteLock lock(db_path_);
  const std::string before = db::ScanTime(std::chrono::system_clock::now());
  std::vector<int> statuses(kScans, 0);
  std::vector<std::thread> scanners;
  scanners.reserve(kScans);
  for (int i = 0; i < kScans; ++i) {
    scanners.emplace_back([&, i] {
      httplib::Client scanner_client("127.0.0.1", server_->port());
      scanner_client.set_read_timeout(60, 0);
      const auto r = scanner_client.Post("/api/v1/detect", scanner(), photo, "image/png");
      statuses[static_cast<std::size_t>(i)] = r ? r->status : -1;
    });
  }
  for (std::thread& t : scanners) t.join();
  // Every scan was answered with the lock still held, and each one waits in memory.
  for (const int status : statuses) EXPECT_EQ(status, 200);
  EXPECT_EQ(ScrapedMetric(client(), "pintag_scan_log_backlog"), kScans);
  const std::string answered = db::ScanTime(std::chrono::system_clock::now());
  EXPECT_TRUE(ScansOnceThereAre(db_path_, 1, false).empty());

  lock.release();
  const std::vector<db::ScanRecord> scans = ScansOnceThereAre(db_path_, kScans, true);
  ASSERT_EQ(scans.size(), static_cast<std::size_t>(kScans));
  for (const db::ScanRecord& scan : scans) {
    // Timed when scanned, not when written.
    EXPECT_GE(scan.scanned_at, before);
    EXPECT_LE(scan.scanned_at, answered);
    EXPECT_EQ(scan.image_bytes, static_cast<std::int64_t>(photo.size()));
    EXPECT_EQ(scan.image_width, 64);
    EXPECT_TRUE(json::parse(scan.result_json)["tags"].empty());
  }
  // The rows are seen at their commit; the backlog drops a moment later, when the log's thread
  // takes its lock back.
  const auto drained_by = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (ScrapedMetric(client(), "pintag_scan_log_backlog") != 0 &&
         std::chrono::steady_clock::now() < drained_by) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_EQ(ScrapedMetric(client(), "pintag_scan_log_backlog"), 0);
  EXPECT_EQ(ScrapedMetric(client(), "pintag_scan_log_failures_total"), 0);
  EXPECT_EQ(ScrapedMetric(client(), "pintag_scans_total"), kScans);
  // The operator is told when answers stopped waiting for their rows, once, and when they wait
  // again (a kill in between loses what was held; serve_crash_test reads the first line).
  const std::string log = ReadFile(dir_.file("stderr.log"));
  const std::string behind = "scans are answered before they are written";
  ASSERT_NE(log.find(behind), std::string::npos) << log;
  EXPECT_EQ(log.find(behind, log.find(behind) + 1), std::string::npos) << log;
  EXPECT_NE(log.find("scan log: caught up; answers wait for their rows again"), std::string::npos)
      << log;
}

TEST_F(ServeTest, AServerStoppedWhileTheLockIsHeldWritesTheScansItHeldBackBeforeItExits) {
  const std::string photo = TaglessPng();
  constexpr int kScans = 3;
  HeldWriteLock lock(db_path_);
  for (int i = 0; i < kScans; ++i) {
    EXPECT_EQ(client().Post("/api/v1/detect", scanner(), photo, "image/png")->status, 200);
  }
  // The lock is released a second into the stop, while the server waits to write its backlog.
  std::thread releaser([&lock] {
    std::this_thread::sleep_for(std::chrono::seconds(1));
    lock.release();
  });
  server_->signal(SIGTERM);
  const int status = server_->wait(30);
  releaser.join();
  EXPECT_EQ(status, 0);
  EXPECT_EQ(ScansOnceThereAre(db_path_, kScans, false).size(), static_cast<std::size_t>(kScans));
  EXPECT_EQ(ReadFile(dir_.file("stderr.log")).find("lost"), std::string::npos);
}

// The scans held back are written after serving ends; a second signal must still stop the server
// at once then (it waited on the log's lock with stop signals unanswered), and say what it left.
TEST_F(ServeTest, ASecondSignalStopsAServerWritingItsBacklogAndSaysWhatItLeft) {
  const std::string photo = TaglessPng();
  constexpr int kScans = 3;
  HeldWriteLock lock(db_path_);  // held until the server is gone
  for (int i = 0; i < kScans; ++i) {
    EXPECT_EQ(client().Post("/api/v1/detect", scanner(), photo, "image/png")->status, 200);
  }
  server_->signal(SIGTERM);
  // Serving ends at once (nothing in flight); the server then waits on the lock for its backlog.
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  EXPECT_TRUE(server_->running());
  server_->signal(SIGTERM);
  EXPECT_EQ(server_->wait(30), 128 + SIGTERM);
  const std::string log = ReadFile(dir_.file("stderr.log"));
  EXPECT_NE(log.find("scan log: up to 3 answered scans held back for it are lost (the stop was "
                     "forced)"),
            std::string::npos)
      << log;
  lock.release();
  EXPECT_TRUE(ScansOnceThereAre(db_path_, 1, false).empty());
}

// An answer over the log's 1 MiB a row (about 330 tags with their poses) was answered and then
// lost from the log. Now the row keeps what each tag read.
TEST_F(ServeTest, AnAnswerTooLargeForTheScanLogIsLoggedAbridgedNotLost) {
  constexpr int kSide = 20;  // 400 tags of 110001's key
  const TagRaster tag = RenderTagRaster(TagKey(11684), {.square_px = 96});
  const int cell = tag.image.width;
  cv::Mat sheet(cell * kSide, cell * kSide, CV_8UC3, cv::Scalar::all(255));
  std::vector<std::uint8_t> rgb = tag.image.pixels;
  const cv::Mat tile(tag.image.height, tag.image.width, CV_8UC3, rgb.data());
  cv::Mat bgr;
  cv::cvtColor(tile, bgr, cv::COLOR_RGB2BGR);
  for (int row = 0; row < kSide; ++row) {
    for (int col = 0; col < kSide; ++col)
      bgr.copyTo(sheet(cv::Rect(col * cell, row * cell, cell, cell)));
  }
  std::vector<std::uint8_t> png;
  ASSERT_TRUE(cv::imencode(".png", sheet, png));
  auto answer =
      client().Post("/api/v1/detect", scanner(), std::string(png.begin(), png.end()), "image/png");
  const json read = ExpectJson(answer);
  ASSERT_EQ(read["tag_count"], kSide * kSide);
  ASSERT_GT(answer->body.size(), db::kMaxJsonBytes) << "the answer must outgrow a log row";

  const std::vector<db::ScanRecord> scans = ScansOnceThereAre(db_path_, 1, true);
  ASSERT_EQ(scans.size(), 1U);
  EXPECT_LE(scans[0].result_json.size(), db::kMaxJsonBytes);
  const json logged = json::parse(scans[0].result_json);
  EXPECT_EQ(logged["scan_log_abridged"], true);
  EXPECT_EQ(logged["tag_count"], kSide * kSide);
  ASSERT_EQ(logged["tags"].size(), static_cast<std::size_t>(kSide * kSide));
  for (std::size_t i = 0; i < logged["tags"].size(); ++i) {
    const json& tag_logged = logged["tags"][i];
    EXPECT_EQ(tag_logged["key"], 11684);
    EXPECT_EQ(tag_logged["pincode"], "110001");
    EXPECT_EQ(tag_logged["bin"], read["tags"][i]["bin"]);
    EXPECT_EQ(tag_logged["centre_px"], read["tags"][i]["centre_px"]);
  }
  EXPECT_FALSE(logged.contains("tags_omitted"));
  EXPECT_EQ(ScrapedMetric(client(), "pintag_scan_log_failures_total"), 0);
}

}  // namespace
}  // namespace pintag::serve_test
