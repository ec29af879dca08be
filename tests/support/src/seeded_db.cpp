#include "pintag/test/seeded_db.hpp"

#include <unistd.h>

#include <filesystem>
#include <stdexcept>

#include "pintag/db/database.hpp"
#include "pintag/test/files.hpp"

namespace pintag::test {
namespace {

/// Seeds `path` atomically: into a private name first, renamed into place when complete.
void SeedInto(const std::string& path) {
  const std::string partial = path + ".partial." + std::to_string(getpid());
  {
    auto opened = db::OpenDatabase(partial);
    if (!opened) throw std::runtime_error(opened.error().message);
  }  // closing checkpoints the WAL into the file and removes it
  std::filesystem::rename(partial, path);
}

std::string SeededInThisProcess() {
  static const TempDir dir("pintag-seeded-");
  static const std::string path = [] {
    std::string file = dir.file("seeded.db");
    SeedInto(file);
    return file;
  }();
  return path;
}

}  // namespace

std::string SeededTemplate(const std::string& cache_dir) {
  if (cache_dir.empty()) return SeededInThisProcess();
  std::error_code error;
  const auto stamp = std::filesystem::last_write_time("/proc/self/exe", error);
  if (error) return SeededInThisProcess();
  std::string cached =
      cache_dir + "/seeded-" + std::to_string(stamp.time_since_epoch().count()) + ".db";
  if (!std::filesystem::exists(cached)) {
    SeedInto(cached);
    // Templates of earlier builds are 35 MB each: drop them.
    for (const auto& entry : std::filesystem::directory_iterator(cache_dir, error)) {
      const std::string name = entry.path().filename().string();
      // Only finished templates: another process may be seeding a ".partial." file now.
      if (name.starts_with("seeded-") && name.ends_with(".db") && entry.path().string() != cached) {
        std::filesystem::remove(entry.path(), error);
      }
    }
  }
  return cached;
}

}  // namespace pintag::test
