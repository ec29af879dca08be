#pragma once
// What the report says about where and when it was measured.

#include <string>

namespace pintag::bench {

struct MachineInfo {
  std::string cpu_model;   ///< /proc/cpuinfo "model name"
  int cores = 0;           ///< std::thread::hardware_concurrency
  std::string load_start;  ///< /proc/loadavg (1, 5, 15 min) before the sweep
  std::string load_end;    ///< … and after
  std::string date_utc;    ///< ISO 8601
  /// The commit the binary was built from ("+ uncommitted changes" when the tree differed), and
  /// the tree's own when it has moved on since.
  std::string commit;
  std::string compiler;
  std::string opencv;
  std::string apriltag;  ///< Debian package version where dpkg knows it
};

/// Everything but load_end.
MachineInfo GatherMachineInfo(const std::string& source_dir);
std::string LoadAverage();

}  // namespace pintag::bench
