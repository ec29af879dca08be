#pragma once
// Shared by the db tests: temporary directories, a seeded database made once per process and
// copied per test, running the `pintag` command.

#include <filesystem>
#include <string>
#include <vector>

#include "pintag/db/database.hpp"

namespace pintag::db::test {

/// A fresh directory under the system temp dir, removed with everything in it.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

/// A seeded database file (seeded once per test process, then copied): its path in `dir`.
std::string CopyOfSeeded(const TempDir& dir, const std::string& name = "registry.db");
/// The path of the once-per-process seeded database (do not modify it).
const std::string& SeededTemplate();

/// Opens an existing database; fails the test (throws) if it cannot.
Connection OpenExisting(const std::string& path);

std::string WriteFile(const std::string& path, const std::string& content);
std::string ReadFile(const std::string& path);

struct CommandResult {
  int exit_code = -1;
  std::string out;  ///< stdout
};
/// Runs a shell command line, capturing stdout (stderr goes to the test log).
CommandResult RunCommand(const std::string& command);
/// The `pintag` executable (PINTAG_EXE), or "" when the build has none.
std::string PintagExe();

/// PRAGMA integrity_check's verdict ("ok" when sound).
std::string IntegrityCheck(Connection& connection);

}  // namespace pintag::db::test
