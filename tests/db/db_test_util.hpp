#pragma once
// Shared by the db tests: temporary directories, a seeded database made once per process and
// copied per test, running the `pintag` command.

#include <filesystem>
#include <string>
#include <vector>

#include "pintag/db/database.hpp"
#include "pintag/test/files.hpp"

namespace pintag::db::test {

using pintag::test::ReadFile;
using pintag::test::TempDir;
using pintag::test::WriteFile;

/// A seeded database file (seeded once per test process, then copied): its path in `dir`.
std::string CopyOfSeeded(const TempDir& dir, const std::string& name = "registry.db");
/// The path of the once-per-process seeded database (do not modify it).
const std::string& SeededTemplate();

/// Opens an existing database; fails the test (throws) if it cannot.
Connection OpenExisting(const std::string& path);

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
