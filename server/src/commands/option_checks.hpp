#pragma once
// CLI11 checks that read option text with the parsers the HTTP routes use, so `pintag` and the
// API read a number or a size the same way and say the same about text that is not one. The
// ranges are each command's own: `pintag render` draws tags from 1 to 1000 mm at 50 to 4800 dpi,
// where the HTTP tag routes take 5 to 500 mm at 72 to 1200 dpi (docs/API.md).

#include <fcntl.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>

#include "app/params.hpp"
#include "commands/commands.hpp"
#include "pintag/codec/file_output.hpp"
#include "pintag/codec/tag_key.hpp"
#include "pintag/db/snapshot.hpp"

namespace pintag::cli {

/// A number that is finite: CLI11's ranges compare with < and >, which NaN passes ("nan" would
/// reach a render as a size of nan mm, or turn the server's body limit off). Put it before them.
inline CLI::Validator FiniteNumber() {
  return {[](std::string& text) -> std::string {
            const std::optional<double> value = app::ParseDecimal(text);
            if (!value) return "must be a decimal number (such as 300 or 0.5), got '" + text + "'";
            if (!std::isfinite(*value)) return "must be a finite number, got '" + text + "'";
            return {};
          },
          "NUMBER"};
}

/// A finite number from `min` to `max`, refused in the routes' words ("must be a number from
/// 0.001 to 1e+07"): CLI::Range printed an unbounded side as DBL_MAX's 309 digits.
inline CLI::Validator NumberFromTo(double min, double max) {
  const std::string range = app::ShownNumber(min) + " to " + app::ShownNumber(max);
  return {[min, max, range](std::string& text) -> std::string {
            const std::optional<double> value = app::ParseDecimal(text);
            if (!value || !std::isfinite(*value) || *value < min || *value > max) {
              return "must be a number from " + range + ", got '" + text + "'";
            }
            return {};
          },
          "NUMBER"};
}

/// Integer text read as decimal, as the HTTP routes read it. CLI11 2.1 converts with strtoll's
/// base 0, so `--key 010` was key 8 and `--port 0x1f90` port 8080: a label for another key. This
/// transform refuses what is not decimal digits (after an optional minus) and drops leading
/// zeros; AddRegisteredCommands puts it first on every integer option but those that read their
/// text themselves (a transform named kReadsItsText, such as TagKeyText).
inline CLI::Validator DecimalInteger() {
  return {[](std::string& text) -> std::string {
            const std::size_t sign = !text.empty() && text.front() == '-' ? 1 : 0;
            const std::size_t digits = text.find_first_not_of("0123456789", sign);
            if (text.size() == sign || digits != std::string::npos) {
              return "must be a whole number in decimal digits, got '" + text + "'";
            }
            const std::size_t first = std::min(text.find_first_not_of('0', sign), text.size() - 1);
            text.erase(sign, first - sign);
            // CLI11 takes strtoll's answer without its range error: 99999999999999999999 was
            // read as 9223372036854775807. No option takes a number of 19 digits.
            if (text.size() - sign > 18) return "is too large: '" + text + "'";
            return {};
          },
          ""};
}

/// The name of a transform that reads an integer option's text whole, in decimal, and leaves it
/// as its number's plain decimal digits.
inline constexpr const char* kReadsItsText = "reads-its-text";

/// A tag key as ParseTagKey reads it (the routes' {key}): 0 to 32767, refused in the route's
/// words. Put on with transform(): it leaves the key's plain digits for CLI11 to convert.
inline CLI::Validator TagKeyText() {
  CLI::Validator validator(
      [](std::string& text) -> std::string {
        const ParsedTagKey parsed = ParseTagKey(text);
        if (parsed) text = std::to_string(parsed.key->value());
        return parsed.error;
      },
      "KEY(0-32767)");
  validator.name(kReadsItsText);
  return validator;
}

/// A file `option` will write, checked before any work is done: a path naming a directory, or in a
/// directory that is not there, is a mistyped path (UsageError), not a failure found at the end.
inline void CheckFileToWrite(const std::string& option, const std::string& path) {
  const std::filesystem::path file(path);
  const std::filesystem::path directory = file.has_parent_path() ? file.parent_path() : ".";
  std::error_code error;
  if (std::filesystem::is_directory(file, error) || (!path.empty() && path.back() == '/')) {
    throw UsageError(option + " " + path + " is a directory; name the file");
  }
  if (!std::filesystem::is_directory(directory, error)) {
    throw UsageError(option + " " + path + ": " + directory.string() + " is not a directory");
  }
}

/// A file `option` replaces whole (a snapshot, a token's secret), checked before any work: not a
/// device, pipe or directory, which the rename would replace with a file (FileReplacedBy), and
/// in a directory that is there, the one the file a link names is in. The path written.
inline std::string CheckFileToReplace(const std::string& option, const std::string& path) {
  CheckFileToWrite(option, path);  // a directory, or one not there, said in its own words
  const FileToReplace target = FileReplacedBy(path);
  if (!target.problem.empty()) throw UsageError(option + " " + target.problem);
  CheckFileToWrite(target.path == path ? option : option + " " + path + ", a link to", target.path);
  return target.path;
}

/// A file name given as an option's value: empty text (an unset shell variable, `--out "$F"`) is
/// refused, where it would mean the option's default or no file at all.
inline CLI::Validator FileName() {
  return {[](const std::string& text) -> std::string {
            return text.empty() ? "needs a file name, got ''" : std::string();
          },
          "FILE"};
}

/// A database file's name: not empty, and not one SQLite reads as a database in memory or a URI
/// (`:memory:`, `file:…`), where every write would be lost when the command ends.
inline CLI::Validator DatabaseFileName() {
  return {[](const std::string& text) -> std::string {
            if (text.empty()) return "needs a file name, got ''";
            if (text == ":memory:" || text.starts_with("file:")) {
              return "must be a file's path, got '" + text +
                     "', which SQLite reads as a database in memory or a URI (write ./" + text +
                     " for a file so named)";
            }
            return {};
          },
          "FILE"};
}

/// The directory `path` is in takes a new file: one is made there and removed (a permission
/// check alone is no proof: root passes it on a read-only mount, and ACLs decide otherwise).
inline void CheckDirectoryWritable(const std::string& option, const std::string& path) {
  const std::filesystem::path file(path);
  const std::filesystem::path directory = file.has_parent_path() ? file.parent_path() : ".";
  const std::filesystem::path probe =
      directory / (".pintag-write-check-" + std::to_string(::getpid()));
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) {
    throw UsageError(option + " " + path + ": cannot write in " + directory.string() + " (" +
                     std::strerror(errno) + ")");
  }
  ::close(fd);
  ::unlink(probe.c_str());
}

/// A file a token's secret is written to (`token create --out`, `serve --admin-token-out`),
/// checked before the database is opened: as CheckFileToReplace, in a directory this user can
/// write (CheckDirectoryWritable), and never a database or a database's file: not `db` itself
/// (through a link or a second name too), nor the -wal, -shm or -journal file of it or of any
/// other SQLite database (DatabaseOwningFile: a scan log's, a snapshot's), nor any file that holds
/// an SQLite database. The secret replaced the registry whole when `--out` named it, and the
/// command said it had done well.
inline void CheckSecretFile(const std::string& option, const std::string& path,
                            const std::string& db) {
  const std::string target = CheckFileToReplace(option, path);
  namespace fs = std::filesystem;
  std::error_code error;
  const fs::path written = fs::weakly_canonical(fs::absolute(target, error), error);
  std::error_code db_error;
  const fs::path database = fs::weakly_canonical(fs::absolute(db, db_error), db_error);
  std::error_code same_error;
  if (fs::equivalent(target, db, same_error) || (!error && !db_error && written == database)) {
    throw UsageError(option + " " + path + " is the database (--db " + db +
                     "), which the secret would replace; name a file of its own");
  }
  // SQLite names a database's files after the file its path resolves to: both names are asked.
  std::string owner;
  for (const std::string& source : {db, database.string()}) {
    for (const std::string& name : {target, written.string()}) {
      if (owner.empty()) owner = db::DatabaseOwningFile(name, source);
    }
  }
  if (!owner.empty()) {
    throw UsageError(option + " " + path + " is a file of the database " + owner +
                     " (its -wal, -shm or -journal), which the secret would corrupt; name a "
                     "file of its own");
  }
  // The first 16 bytes of every SQLite database file. Read before this process opens any
  // database: closing a descriptor drops the POSIX locks the process holds on that file, SQLite's
  // connections' included (db/src/database.cpp).
  constexpr char kSqliteHeader[] = "SQLite format 3";
  char head[sizeof kSqliteHeader] = {};
  if (const int fd = ::open(target.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK); fd >= 0) {
    const ssize_t got = ::read(fd, head, sizeof head);
    ::close(fd);
    if (got == static_cast<ssize_t>(sizeof head) &&
        std::memcmp(head, kSqliteHeader, sizeof head) == 0) {
      throw UsageError(option + " " + path +
                       " holds an SQLite database, which the secret would replace; name a file "
                       "of its own");
    }
  }
  CheckDirectoryWritable(option, target);
}

}  // namespace pintag::cli
