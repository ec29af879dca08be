#include "db_test_util.hpp"

#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace pintag::db::test {

TempDir::TempDir() {
  std::string pattern = (std::filesystem::temp_directory_path() / "pintag-db-XXXXXX").string();
  if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
  path_ = pattern;
}

TempDir::~TempDir() {
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

namespace {

/// Seeds `path` atomically: into a private name first, renamed into place when complete.
void SeedInto(const std::string& path) {
  const std::string partial = path + ".partial." + std::to_string(getpid());
  {
    auto opened = OpenDatabase(partial);
    if (!opened) throw std::runtime_error(opened.error().message);
  }  // closing checkpoints the WAL into the file and removes it
  std::filesystem::rename(partial, path);
}

}  // namespace

// ctest runs every test in its own process; seeding once per build of test_db (not once per
// process) keeps the suite fast. The template is named after the executable's modification time,
// so a rebuilt test_db (new seed, new schema) never sees an old one.
const std::string& SeededTemplate() {
  static const TempDir dir;
  static const std::string path = [] {
#ifdef PINTAG_TEST_TEMPLATE_DIR
    std::error_code error;
    const auto stamp = std::filesystem::last_write_time("/proc/self/exe", error);
    if (!error) {
      std::string cached = std::string(PINTAG_TEST_TEMPLATE_DIR) + "/seeded-" +
                           std::to_string(stamp.time_since_epoch().count()) + ".db";
      if (!std::filesystem::exists(cached)) {
        SeedInto(cached);
        // Templates of earlier builds are 35 MB each: drop them.
        for (const auto& entry :
             std::filesystem::directory_iterator(PINTAG_TEST_TEMPLATE_DIR, error)) {
          const std::string name = entry.path().filename().string();
          // Only finished templates: another process may be seeding a ".partial." file now.
          if (name.starts_with("seeded-") && name.ends_with(".db") &&
              entry.path().string() != cached) {
            std::filesystem::remove(entry.path(), error);
          }
        }
      }
      return cached;
    }
#endif
    std::string file = dir.file("seeded.db");
    SeedInto(file);
    return file;
  }();
  return path;
}

std::string CopyOfSeeded(const TempDir& dir, const std::string& name) {
  std::string target = dir.file(name);
  std::filesystem::copy_file(SeededTemplate(), target);
  return target;
}

Connection OpenExisting(const std::string& path) {
  auto opened = OpenDatabase(path, {.create = false});
  if (!opened) throw std::runtime_error(opened.error().message);
  return std::move(opened).value().connection;
}

std::string WriteFile(const std::string& path, const std::string& content) {
  std::ofstream out(path, std::ios::binary);
  out << content;
  if (!out.flush()) throw std::runtime_error("cannot write " + path);
  return path;
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

CommandResult RunCommand(const std::string& command) {
  CommandResult result;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) throw std::runtime_error("popen failed");
  char buffer[65536];
  std::size_t got = 0;
  while ((got = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) result.out.append(buffer, got);
  const int status = pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

std::string PintagExe() {
#ifdef PINTAG_EXE
  return PINTAG_EXE;
#else
  return "";
#endif
}

std::string IntegrityCheck(Connection& connection) {
  Statement check = connection.prepare("PRAGMA integrity_check");
  std::string verdict;
  while (check.step()) verdict += check.getText(0);
  return verdict;
}

}  // namespace pintag::db::test
