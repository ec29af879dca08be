#pragma once
// Prometheus metrics: request counts and latency histograms by route, method and status, named
// counters the application increments (detections, labels rendered, …), and gauges read when
// scraped (a replica's follow status). Thread-safe.

#include <array>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

namespace pintag::server {

class Metrics {
 public:
  /// Latency bucket upper bounds in seconds (the +Inf bucket is implicit).
  static constexpr std::array<double, 12> kBuckets = {0.001, 0.005, 0.01, 0.025, 0.05, 0.1,
                                                      0.25,  0.5,   1,    2.5,   5,    10};

  /// One finished request. `route` is the route's pattern (bounded cardinality), or "unmatched"
  /// / "static" for requests outside the table. A method outside HTTP's standard ones is counted
  /// as "other": a client sending made-up methods must not add series without end.
  void observeRequest(std::string_view route, std::string_view method, int status, double seconds);

  /// Declares a counter so it is exported (as 0) before its first increment. `name` must be a
  /// Prometheus metric name ending in "_total", e.g. "pintag_labels_rendered_total".
  void defineCounter(std::string_view name, std::string_view help);
  /// Adds `by` to a counter (defined on first use, with an empty help text).
  void increment(std::string_view name, double by = 1);
  /// Current value of a counter; 0 when unknown.
  double counter(std::string_view name) const;
  /// Requests observed with this route, method and status.
  long long requestCount(std::string_view route, std::string_view method, int status) const;

  /// A gauge's value at one scrape. `name` is a Prometheus metric name without a "_total" end.
  struct Gauge {
    std::string name;
    std::string help;
    double value = 0;
  };
  /// Called on every scrape, outside the metrics' lock, for gauges whose value lives elsewhere.
  /// A gauge it leaves out is not exported at that scrape (a time that has not happened yet).
  using GaugeSource = std::function<std::vector<Gauge>()>;
  void addGaugeSource(GaugeSource source);

  /// The text exposition format, version 0.0.4 (content type kContentType).
  std::string renderPrometheus() const;
  static constexpr std::string_view kContentType = "text/plain; version=0.0.4; charset=utf-8";

 private:
  struct Histogram {
    std::array<long long, kBuckets.size()> buckets{};  // non-cumulative counts per bucket
    long long count = 0;
    double sum = 0;
  };
  struct Counter {
    std::string help;
    double value = 0;
  };
  using Key = std::tuple<std::string, std::string, int>;  // route, method, status

  mutable std::mutex mutex_;
  std::map<Key, Histogram> requests_;
  std::map<std::string, Counter, std::less<>> counters_;
  std::vector<GaugeSource> gauge_sources_;
};

}  // namespace pintag::server
