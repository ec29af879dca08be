#include "commands/open_db.hpp"

#include <array>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string_view>
#include <utility>

#include "pintag/db/database.hpp"
#include "pintag/db/snapshot.hpp"
#include "replica/snapshot_watcher.hpp"

namespace pintag::cli {

std::string LockedMessage(const std::string& path, const std::string& not_done) {
  return path +
         " is being written by another process (an import, or `pintag serve` writing) and "
         "stayed locked for 5 s; " +
         not_done + ". Try again when it is done";
}

std::string DatabaseWriteFailure(const std::string& path, const db::Error& error,
                                 const std::string& not_done) {
  switch (error.code) {
    case db::ErrorCode::kReadOnly:
      return path + " cannot be written: the file or its directory is read-only to this user (" +
             error.message + "); " + not_done;
    case db::ErrorCode::kNoSpace:
      return "the disk holding " + path + " is full (" + error.message + "); " + not_done;
    case db::ErrorCode::kStorage:
      return (error.message.find("database " + path) != std::string::npos
                  ? error.message
                  : path + ": " + error.message) +
             "; " + not_done;
    default:
      return {};
  }
}

namespace {

/// Refuses a file a running replica serves: opened read-write, it is switched to WAL and written.
void RefuseAReplicasSnapshot(const std::string& path) {
  if (replica::AReplicaServes(path)) {
    throw std::runtime_error(
        path +
        " is the snapshot a running replica serves: a change written there would be that "
        "replica's alone, with keys the primary does not have. Give the primary's "
        "database; its replicas take the change with their next snapshot");
  }
}

/// Refuses a database in rollback-journal mode (a snapshot or backup copied in to restore a
/// primary) with a non-empty write-ahead log beside it: that log is the replaced database's, left
/// by an unclean stop, and SQLite takes a -wal file it finds as the file's own, applying it at the
/// first read: the restore undone without a word, or the file damaged while the server said ready
/// (an operator walkthrough, 2026-12-08). The header is read with a descriptor of this function's
/// own, so it runs before the process opens any connection to the file (closing a descriptor
/// drops every POSIX lock the process holds on it): each command opens its database here, first.
void RefuseAStaleWriteAheadLog(const std::string& path) {
  std::error_code error;
  const std::string wal = path + "-wal";
  const std::uintmax_t wal_bytes = std::filesystem::file_size(wal, error);
  if (error || wal_bytes == 0 || !std::filesystem::is_regular_file(path, error)) return;
  std::array<char, 20> header{};
  std::ifstream file(path, std::ios::binary);
  if (!file.read(header.data(), header.size())) return;
  const bool sqlite =
      std::string_view(header.data(), 16) == std::string_view("SQLite format 3\0", 16);
  // Bytes 18 and 19, the write and read versions: 1 for a rollback journal, 2 for WAL.
  if (!sqlite || header[18] != 1 || header[19] != 1) return;
  throw std::runtime_error(
      "database " + path + " is in rollback-journal mode (a snapshot or backup copied in), but " +
      wal + " (" + std::to_string(wal_bytes) +
      " bytes), a write-ahead log left by the database it replaced, is beside it: SQLite would "
      "apply that log to it, undoing the copy or damaging it. With no server running on " +
      path + ", delete " + wal + " and " + path + "-shm, then start again");
}

}  // namespace

db::Connection OpenDb(const std::string& path, const SayFunction& say) {
  RefuseAReplicasSnapshot(path);
  RefuseAStaleWriteAheadLog(path);
  std::error_code error;
  const bool existed = std::filesystem::exists(path, error);
  const auto tell = [&say](const std::string& what) {
    if (say) {
      say(what);
    } else {
      std::cerr << what << "\n";
    }
  };
  db::OpenOptions options;
  // Seeding takes seconds (about 10 on a busy machine), during which nothing else is said.
  options.before_seeding = [&] {
    tell("seeding " + path + " from " + db::SeedSource() + " (a few seconds)...");
  };
  auto opened = db::OpenDatabase(path, options);
  if (!opened && opened.error().code == db::ErrorCode::kBusy) {
    throw std::runtime_error(LockedMessage(path, "it could not be opened"));
  }
  if (!opened) {
    // Named once: most of OpenDatabase's messages name the file already; SQLite's do not.
    const std::string& message = opened.error().message;
    throw std::runtime_error(
        message.find("database " + path) != std::string::npos ? message : path + ": " + message);
  }
  if (opened->created) {
    // An empty file (`touch`, or a mount's placeholder) is a new database to SQLite.
    const std::string what = existed
                                 ? "seeded the empty file " + path + " from " + db::SeedSource()
                                 : "created " + path + " and seeded it from " + db::SeedSource();
    tell(what);
  }
  return std::move(opened).value().connection;
}

db::Connection OpenExistingDb(const std::string& path) {
  RefuseAReplicasSnapshot(path);
  RefuseAStaleWriteAheadLog(path);
  std::error_code error;
  if (!std::filesystem::exists(path, error)) {
    throw std::runtime_error(
        "no database at " + path +
        " (`pintag serve`, `pintag import` or `pintag token create` makes one)");
  }
  // An empty file is a new database to OpenDb, which would seed 35 MB into it to list no tokens.
  if (std::filesystem::is_regular_file(path, error) &&
      std::filesystem::file_size(path, error) == 0) {
    throw std::runtime_error(path +
                             " is empty: not a PinTag database (`pintag serve`, `pintag import` or "
                             "`pintag token create` makes one)");
  }
  return OpenDb(path);
}

db::Connection OpenForReading(const std::string& path, bool must_exist) {
  std::error_code error;
  if (std::filesystem::is_regular_file(path, error) && db::LiveDatabaseAt(path).empty()) {
    // A registry of this schema, read as it is. Anything else (an older registry to migrate,
    // another application's database, no database) goes through OpenDb, which says what it is.
    try {
      db::Connection connection(path, {.create = false, .read_only = true});
      // The version alone is a number any program may set: the registry's tables must be there.
      if (db::SchemaVersion(connection) == db::kSchemaVersion &&
          connection.queryInt64("SELECT count(*) FROM sqlite_master WHERE type = 'table' AND "
                                "name IN ('pincodes', 'tag_keys')") == 2) {
        return connection;
      }
    } catch (const std::exception&) {
    }
  }
  return must_exist ? OpenExistingDb(path) : OpenDb(path);
}

}  // namespace pintag::cli
