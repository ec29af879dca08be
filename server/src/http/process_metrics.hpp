#pragma once
// The standard process_* metrics of Prometheus client libraries, read from /proc and getrusage.

#include <string>

namespace pintag::server {

/// process_resident_memory_bytes, process_virtual_memory_bytes, process_cpu_seconds_total,
/// process_open_fds, process_max_fds and process_start_time_seconds, in the text exposition
/// format. A value /proc does not give (not Linux) is left out rather than reported as 0.
std::string ProcessMetricsText();

}  // namespace pintag::server
