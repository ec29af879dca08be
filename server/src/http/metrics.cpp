#include "pintag/server/metrics.hpp"

#include <cstdio>
#include <set>

namespace pintag::server {
namespace {

// Label values escape backslash, double quote and newline (exposition format).
std::string Escape(std::string_view value) {
  std::string out;
  for (char c : value) {
    if (c == '\\') {
      out += "\\\\";
    } else if (c == '"') {
      out += "\\\"";
    } else if (c == '\n') {
      out += "\\n";
    } else {
      out += c;
    }
  }
  return out;
}

/// The method as a label value: one of RFC 9110's methods (and PATCH), else "other". cpp-httplib
/// fills in the request's method before it refuses one it does not know, so without this every
/// made-up method of a 400 answer became a series of its own.
std::string_view MethodLabel(std::string_view method) {
  for (std::string_view known :
       {"GET", "HEAD", "POST", "PUT", "DELETE", "CONNECT", "OPTIONS", "TRACE", "PATCH"}) {
    if (method == known) return known;
  }
  return "other";
}

std::string Number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.15g", value);
  return text;
}

}  // namespace

void Metrics::observeRequest(std::string_view route, std::string_view method, int status,
                             double seconds) {
  const std::lock_guard lock(mutex_);
  Histogram& h = requests_[Key{std::string(route), std::string(MethodLabel(method)), status}];
  std::size_t bucket = 0;
  while (bucket < kBuckets.size() && seconds > kBuckets[bucket]) ++bucket;
  if (bucket < kBuckets.size()) ++h.buckets[bucket];
  ++h.count;
  h.sum += seconds;
}

void Metrics::defineCounter(std::string_view name, std::string_view help) {
  const std::lock_guard lock(mutex_);
  auto it = counters_.find(name);
  if (it == counters_.end()) it = counters_.emplace(std::string(name), Counter{}).first;
  it->second.help = std::string(help);
}

void Metrics::increment(std::string_view name, double by) {
  const std::lock_guard lock(mutex_);
  auto it = counters_.find(name);
  if (it == counters_.end()) it = counters_.emplace(std::string(name), Counter{}).first;
  it->second.value += by;
}

double Metrics::counter(std::string_view name) const {
  const std::lock_guard lock(mutex_);
  const auto it = counters_.find(name);
  return it == counters_.end() ? 0 : it->second.value;
}

long long Metrics::requestCount(std::string_view route, std::string_view method, int status) const {
  const std::lock_guard lock(mutex_);
  const auto it = requests_.find(Key{std::string(route), std::string(method), status});
  return it == requests_.end() ? 0 : it->second.count;
}

void Metrics::addGaugeSource(GaugeSource source) {
  const std::lock_guard lock(mutex_);
  gauge_sources_.push_back(std::move(source));
}

std::string Metrics::renderPrometheus() const {
  std::vector<GaugeSource> sources;
  {
    const std::lock_guard lock(mutex_);
    sources = gauge_sources_;
  }
  std::string gauges;
  for (const GaugeSource& source : sources) {
    for (const Gauge& gauge : source()) {
      if (!gauge.help.empty()) gauges += "# HELP " + gauge.name + " " + gauge.help + "\n";
      gauges += "# TYPE " + gauge.name + " gauge\n";
      gauges += gauge.name + " " + Number(gauge.value) + "\n";
    }
  }
  const std::lock_guard lock(mutex_);
  std::string out;
  out += "# HELP pintag_http_requests_total HTTP requests answered, by route, method and status.\n";
  out += "# TYPE pintag_http_requests_total counter\n";
  for (const auto& [key, h] : requests_) {
    const auto& [route, method, status] = key;
    out += "pintag_http_requests_total{route=\"" + Escape(route) + "\",method=\"" + Escape(method) +
           "\",status=\"" + std::to_string(status) + "\"} " + std::to_string(h.count) + "\n";
  }
  out +=
      "# HELP pintag_http_request_duration_seconds Time from a request's head arriving to its "
      "answer written.\n";
  out += "# TYPE pintag_http_request_duration_seconds histogram\n";
  for (const auto& [key, h] : requests_) {
    const auto& [route, method, status] = key;
    const std::string labels = "route=\"" + Escape(route) + "\",method=\"" + Escape(method) +
                               "\",status=\"" + std::to_string(status) + "\"";
    long long cumulative = 0;
    for (std::size_t i = 0; i < kBuckets.size(); ++i) {
      cumulative += h.buckets[i];
      out += "pintag_http_request_duration_seconds_bucket{" + labels + ",le=\"" +
             Number(kBuckets[i]) + "\"} " + std::to_string(cumulative) + "\n";
    }
    out += "pintag_http_request_duration_seconds_bucket{" + labels + ",le=\"+Inf\"} " +
           std::to_string(h.count) + "\n";
    out += "pintag_http_request_duration_seconds_sum{" + labels + "} " + Number(h.sum) + "\n";
    out += "pintag_http_request_duration_seconds_count{" + labels + "} " + std::to_string(h.count) +
           "\n";
  }
  for (const auto& [name, c] : counters_) {
    if (!c.help.empty()) out += "# HELP " + name + " " + c.help + "\n";
    out += "# TYPE " + name + " counter\n";
    out += name + " " + Number(c.value) + "\n";
  }
  return out + gauges;
}

}  // namespace pintag::server
