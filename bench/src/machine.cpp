#include "machine.hpp"

#include <array>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <opencv2/core/version.hpp>
#include <thread>

namespace pintag::bench {

extern const char kBuildCommit[];  // build_commit.cpp, written at build time
namespace {

std::string Trim(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ' || s.back() == '\r')) s.pop_back();
  std::size_t i = 0;
  while (i < s.size() && s[i] == ' ') ++i;
  return s.substr(i);
}

// Output of a shell command, "" when it fails.
std::string Run(const std::string& command) {
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return "";
  std::string out;
  std::array<char, 256> buf{};
  while (std::fgets(buf.data(), static_cast<int>(buf.size()), pipe) != nullptr) out += buf.data();
  return pclose(pipe) == 0 ? Trim(out) : "";
}

}  // namespace

std::string LoadAverage() {
  std::ifstream in("/proc/loadavg");
  double a = 0, b = 0, c = 0;
  if (!(in >> a >> b >> c)) return "unknown";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.2f, %.2f, %.2f", a, b, c);
  return buf;
}

MachineInfo GatherMachineInfo(const std::string& source_dir) {
  MachineInfo info;
  std::ifstream cpuinfo("/proc/cpuinfo");
  for (std::string line; std::getline(cpuinfo, line);) {
    if (line.rfind("model name", 0) == 0) {
      info.cpu_model = Trim(line.substr(line.find(':') + 1));
      break;
    }
  }
  if (info.cpu_model.empty()) info.cpu_model = "unknown";
  info.cores = static_cast<int>(std::thread::hardware_concurrency());
  info.load_start = LoadAverage();
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&now, &tm);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", &tm);
  info.date_utc = date;
  // The commit the binary was built from. A tree moved on since (another commit checked out, or
  // uncommitted changes where the build had none) is said beside it: the report describes the
  // code that ran. Edits made after a build from a tree already changed go unseen.
  info.commit = kBuildCommit;
  const std::string git = "git --no-optional-locks -C '" + source_dir + "' ";
  std::string now_at = Run(git + "rev-parse --short=12 HEAD 2>/dev/null");
  if (!now_at.empty() &&
      !Run(git + "status --porcelain --untracked-files=no 2>/dev/null").empty()) {
    now_at += " + uncommitted changes in the working tree";
  }
  if (!now_at.empty() && now_at != info.commit) {
    info.commit += " (the source tree is now at " + now_at + ")";
  }
#if defined(__clang__)
  info.compiler = "clang " __clang_version__;
#elif defined(__GNUC__)
  info.compiler = "g++ " __VERSION__;
#endif
#ifdef NDEBUG
  info.compiler += ", NDEBUG";
#else
  info.compiler += ", assertions on (not a Release build)";
#endif
  info.opencv = CV_VERSION;
  info.apriltag = Run("dpkg-query -W -f='${Version}' libapriltag3 2>/dev/null");
  if (info.apriltag.empty()) info.apriltag = "unknown version";
  return info;
}

}  // namespace pintag::bench
