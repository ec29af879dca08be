#include "process_metrics.hpp"

#include <dirent.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <optional>
#include <sstream>

namespace pintag::server {
namespace {

void Add(std::string& out, const char* name, const char* type, const char* help,
         std::optional<double> value) {
  if (!value) return;
  char number[40];
  std::snprintf(number, sizeof number, "%.15g", *value);
  out += std::string("# HELP ") + name + " " + help + "\n# TYPE " + name + " " + type + "\n" +
         name + " " + number + "\n";
}

/// /proc/self/statm: total and resident pages.
std::optional<std::pair<double, double>> MemoryBytes() {
  std::ifstream statm("/proc/self/statm");
  double total_pages = 0;
  double resident_pages = 0;
  if (!(statm >> total_pages >> resident_pages)) return std::nullopt;
  const double page = static_cast<double>(::sysconf(_SC_PAGESIZE));
  return std::pair{total_pages * page, resident_pages * page};
}

std::optional<double> CpuSeconds() {
  rusage usage{};
  if (::getrusage(RUSAGE_SELF, &usage) != 0) return std::nullopt;
  const auto seconds = [](const timeval& t) {
    return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_usec) / 1e6;
  };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

std::optional<double> OpenFds() {
  DIR* dir = ::opendir("/proc/self/fd");
  if (dir == nullptr) return std::nullopt;
  double count = 0;
  while (const dirent* entry = ::readdir(dir)) {
    if (entry->d_name[0] != '.') ++count;
  }
  ::closedir(dir);
  return count - 1;  // the directory stream's own descriptor
}

std::optional<double> MaxFds() {
  rlimit limit{};
  if (::getrlimit(RLIMIT_NOFILE, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY)
    return std::nullopt;
  return static_cast<double>(limit.rlim_cur);
}

/// Boot time (/proc/stat btime) plus the process's start in clock ticks after boot (field 22 of
/// /proc/self/stat, counted after the parenthesised command name, which may hold spaces).
std::optional<double> StartTimeSeconds() {
  static const std::optional<double> start = []() -> std::optional<double> {
    std::ifstream stat_file("/proc/self/stat");
    std::stringstream text;
    text << stat_file.rdbuf();
    const std::string stat = text.str();
    const std::size_t close = stat.rfind(')');
    if (close == std::string::npos) return std::nullopt;
    std::istringstream fields(stat.substr(close + 2));
    std::string field;
    for (int i = 3; i <= 22 && (fields >> field); ++i) {
    }
    double ticks = 0;
    try {
      ticks = std::stod(field);
    } catch (const std::exception&) {
      return std::nullopt;
    }
    std::ifstream boot("/proc/stat");
    std::string line;
    while (std::getline(boot, line)) {
      if (line.rfind("btime ", 0) == 0) {
        return std::stod(line.substr(6)) + ticks / static_cast<double>(::sysconf(_SC_CLK_TCK));
      }
    }
    return std::nullopt;
  }();
  return start;
}

}  // namespace

std::string ProcessMetricsText() {
  std::string out;
  const auto memory = MemoryBytes();
  Add(out, "process_resident_memory_bytes", "gauge", "Resident memory size in bytes.",
      memory ? std::optional(memory->second) : std::nullopt);
  Add(out, "process_virtual_memory_bytes", "gauge", "Virtual memory size in bytes.",
      memory ? std::optional(memory->first) : std::nullopt);
  Add(out, "process_cpu_seconds_total", "counter", "Total user and system CPU time in seconds.",
      CpuSeconds());
  Add(out, "process_open_fds", "gauge", "Number of open file descriptors.", OpenFds());
  Add(out, "process_max_fds", "gauge", "Maximum number of open file descriptors.", MaxFds());
  Add(out, "process_start_time_seconds", "gauge",
      "Start time of the process since the Unix epoch in seconds.", StartTimeSeconds());
  return out;
}

}  // namespace pintag::server
