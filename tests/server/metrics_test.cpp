#include "pintag/server/metrics.hpp"

#include <gtest/gtest.h>

#include <thread>
#include <vector>

namespace pintag::server {
namespace {

TEST(Metrics, HistogramBucketsAreCumulative) {
  Metrics m;
  m.observeRequest("/a", "GET", 200, 0.0005);
  m.observeRequest("/a", "GET", 200, 0.02);
  m.observeRequest("/a", "GET", 200, 30);
  const std::string text = m.renderPrometheus();
  const std::string labels = R"(route="/a",method="GET",status="200")";
  EXPECT_NE(
      text.find("pintag_http_request_duration_seconds_bucket{" + labels + R"(,le="0.001"} 1)"),
      std::string::npos)
      << text;
  EXPECT_NE(text.find("pintag_http_request_duration_seconds_bucket{" + labels + R"(,le="0.01"} 1)"),
            std::string::npos);
  EXPECT_NE(
      text.find("pintag_http_request_duration_seconds_bucket{" + labels + R"(,le="0.025"} 2)"),
      std::string::npos);
  EXPECT_NE(text.find("pintag_http_request_duration_seconds_bucket{" + labels + R"(,le="10"} 2)"),
            std::string::npos);
  EXPECT_NE(text.find("pintag_http_request_duration_seconds_bucket{" + labels + R"(,le="+Inf"} 3)"),
            std::string::npos);
  EXPECT_NE(text.find("pintag_http_request_duration_seconds_count{" + labels + "} 3"),
            std::string::npos);
  EXPECT_NE(text.find("pintag_http_requests_total{" + labels + "} 3"), std::string::npos);
  EXPECT_NE(text.find("# TYPE pintag_http_request_duration_seconds histogram"), std::string::npos);
}

TEST(Metrics, NamedCountersAreExportedFromDefinition) {
  Metrics m;
  m.defineCounter("pintag_detections_total", "Tags detected.");
  std::string text = m.renderPrometheus();
  EXPECT_NE(text.find("# HELP pintag_detections_total Tags detected.\n"), std::string::npos);
  EXPECT_NE(text.find("# TYPE pintag_detections_total counter\npintag_detections_total 0\n"),
            std::string::npos)
      << text;
  m.increment("pintag_detections_total", 3);
  m.increment("pintag_detections_total");
  EXPECT_EQ(m.counter("pintag_detections_total"), 4);
  EXPECT_NE(m.renderPrometheus().find("pintag_detections_total 4\n"), std::string::npos);
  EXPECT_EQ(m.counter("unknown_total"), 0);
}

// A gauge is read at each scrape: its value then, and none at all while its source leaves it out.
TEST(Metrics, GaugesAreReadFromTheirSourceAtEachScrape) {
  Metrics m;
  double level = 0;
  m.addGaugeSource([&level] {
    std::vector<Metrics::Gauge> gauges = {{"pintag_test_level", "A level.", level}};
    if (level > 1) gauges.push_back({"pintag_test_high_since_seconds", "", 1.5e9});
    return gauges;
  });
  std::string text = m.renderPrometheus();
  EXPECT_NE(text.find("# HELP pintag_test_level A level.\n# TYPE pintag_test_level gauge\n"
                      "pintag_test_level 0\n"),
            std::string::npos)
      << text;
  EXPECT_EQ(text.find("pintag_test_high_since_seconds"), std::string::npos) << text;
  level = 2.5;
  text = m.renderPrometheus();
  EXPECT_NE(text.find("\npintag_test_level 2.5\n"), std::string::npos) << text;
  EXPECT_NE(text.find("# TYPE pintag_test_high_since_seconds gauge\n"
                      "pintag_test_high_since_seconds 1500000000\n"),
            std::string::npos)
      << text;
}

TEST(Metrics, EscapesLabelValues) {
  Metrics m;
  m.observeRequest("a\"b\\c\nd", "GET", 404, 0);
  EXPECT_NE(m.renderPrometheus().find(R"(route="a\"b\\c\nd")"), std::string::npos);
}

TEST(Metrics, IsThreadSafe) {
  Metrics m;
  std::vector<std::thread> threads;
  threads.reserve(4);
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&m] {
      for (int i = 0; i < 1000; ++i) {
        m.observeRequest("/x", "GET", 200, 0.001);
        m.increment("pintag_labels_rendered_total");
      }
    });
  }
  for (auto& t : threads) t.join();
  EXPECT_EQ(m.requestCount("/x", "GET", 200), 4000);
  EXPECT_EQ(m.counter("pintag_labels_rendered_total"), 4000);
}

}  // namespace
}  // namespace pintag::server
