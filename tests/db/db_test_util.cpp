#include "db_test_util.hpp"

#include <sys/wait.h>

#include <cstdio>
#include <memory>
#include <stdexcept>

#include "pintag/test/seeded_db.hpp"

namespace pintag::db::test {

// ctest runs every test in its own process; seeding once per build of test_db (not once per
// process) keeps the suite fast.
const std::string& SeededTemplate() {
  static const std::string path = pintag::test::SeededTemplate(PINTAG_TEST_TEMPLATE_DIR);
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
