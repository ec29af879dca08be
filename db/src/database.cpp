#include "pintag/db/database.hpp"

#include <filesystem>
#include <optional>
#include <string>

#include "guard.hpp"
#include "schema.hpp"

namespace pintag::db {
namespace {

/// What a file holds before it is taken as a registry.
struct FileSchema {
  int version = 0;           ///< PRAGMA user_version
  std::int64_t objects = 0;  ///< tables, indexes, views and triggers; none in a new or empty file
  std::string names;         ///< the first few table and view names, for a message
  bool registry_tables = false;  ///< `pincodes` and `tag_keys`, which every PinTag version has
};

/// Read in one statement, so that a pintag creating the file at the same moment (its schema and
/// version in one transaction) is seen before or after that, never halfway.
FileSchema ReadFileSchema(Connection& connection) {
  Statement read = connection.prepare(
      "SELECT user_version, (SELECT count(*) FROM sqlite_master), "
      "(SELECT group_concat(name, ', ') FROM (SELECT name FROM sqlite_master "
      "WHERE type IN ('table', 'view') ORDER BY name LIMIT 3)), "
      "(SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name IN ('pincodes', "
      "'tag_keys')) FROM pragma_user_version");
  read.step();
  return {read.getInt(0), read.getInt64(1), read.getText(2), read.getInt(3) == 2};
}

/// An SQLite file PinTag did not write: version 0 and yet tables (each migration step sets the
/// version in the transaction that creates its tables), or a version without PinTag's registry
/// tables (another program's user_version, a browser's history at 74). Seeding it would put
/// PinTag's schema and 154,874 offices into someone else's data; even switching it to WAL would
/// change their file.
std::optional<Error> RefuseForeignFile(const std::string& path, const FileSchema& schema) {
  if (schema.objects == 0 || (schema.version != 0 && schema.registry_tables)) return std::nullopt;
  const std::string holds = schema.names.empty() ? "a schema" : "tables (" + schema.names + ")";
  return Error{ErrorCode::kConflict,
               "database " + path + " is not a PinTag database: it already holds " + holds +
                   (schema.version == 0 ? " and no PinTag schema version"
                                        : " and schema version " + std::to_string(schema.version) +
                                              " but not PinTag's tables") +
                   "; give a PinTag database, or a new or empty file to create one in"};
}

/// Why no database file can be at `path`, said before SQLite is asked (it said "unable to open
/// database file" for a directory or a missing directory, and "disk I/O error" for /dev/null):
/// a directory, device, pipe or socket there, or no directory to make the file in. Empty when
/// none of these.
std::string NoDatabaseFileAt(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code error;
  const fs::file_status status = fs::status(path, error);
  if (fs::exists(status)) {
    if (fs::is_regular_file(status)) return {};
    const char* what = fs::is_directory(status) ? "a directory"
                       : fs::is_fifo(status)    ? "a pipe"
                       : fs::is_socket(status)  ? "a socket"
                                                : "a device";
    return "database " + path + " is " + what + ", not a database file";
  }
  if (!path.empty() && path.back() == '/') {
    return "database " + path + " names a directory (it ends in /), not a database file";
  }
  const fs::path directory = fs::absolute(path, error).parent_path();
  // Only a directory known not to be there; one that cannot be looked at is SQLite's to say.
  if (!error && !fs::exists(fs::status(directory, error)) &&
      (!error || error == std::errc::no_such_file_or_directory)) {
    return "database " + path + " cannot be made: its directory " + directory.string() +
           " is not there";
  }
  return {};
}

/// SQLite's smallest database file: one page of the smallest size. A file of 1 to 511 bytes is no
/// database, told from its size alone (SQLite took a file of one byte for an empty database, and
/// seeded over it). The file is not opened to read its header: closing any descriptor of a file
/// drops every POSIX lock this process holds on it, the locks of SQLite's own connections
/// included, and a server opens its database while other connections hold it.
constexpr std::uintmax_t kSmallestDatabaseBytes = 512;

/// SQLite's SQLITE_NOTADB: a file that does not start as a database, found on its first read.
constexpr int kSqliteNotADatabase = 26;

std::string NotADatabase(const std::string& path, std::uintmax_t bytes) {
  // "that do not start as one" was wrong for a file whose header is SQLite's and whose rest is
  // damaged, which SQLite refuses the same way.
  return "database " + path + " is not an SQLite database (" + std::to_string(bytes) +
         (bytes == 1 ? " byte" : " bytes") +
         " that SQLite cannot read as one); give a PinTag database, or a new or empty file to "
         "create one in";
}

}  // namespace

Result<OpenedDatabase> OpenDatabase(const std::string& path, const OpenOptions& options) {
  try {
    std::error_code ignored;
    const bool exists = std::filesystem::exists(path, ignored);
    if (!options.create && !exists) {
      return Error{ErrorCode::kNotFound, "database " + path + " does not exist"};
    }
    if (const std::string problem = NoDatabaseFileAt(path); !problem.empty()) {
      return Error{exists ? ErrorCode::kConflict : ErrorCode::kNotFound, problem};
    }
    if (!exists) {
      // A write-ahead log without its database holds writes of a file that was moved or deleted
      // while a server had it open. A database made here would take that log as its own.
      const std::string wal = path + "-wal";
      const auto wal_bytes = std::filesystem::file_size(wal, ignored);
      if (!ignored && wal_bytes > 0) {
        return Error{ErrorCode::kConflict,
                     "database " + path + " is missing but its write-ahead log " + wal + " (" +
                         std::to_string(wal_bytes) +
                         " bytes) is there: the database was moved or deleted while it was open. "
                         "Put the database file back at " +
                         path + ", or move " + wal + " and " + path +
                         "-shm aside to start a new registry"};
      }
    }
    std::uintmax_t bytes = 0;
    if (exists) {
      bytes = std::filesystem::file_size(path, ignored);
      if (ignored) bytes = 0;
      if (bytes > 0 && bytes < kSmallestDatabaseBytes) {
        return Error{ErrorCode::kConflict, NotADatabase(path, bytes)};
      }
    }
    // SQLite's "file is not a database" (from the connection's first statement) named no file.
    std::optional<OpenedDatabase> made;
    FileSchema schema;
    try {
      made.emplace(OpenedDatabase{Connection(path, {.create = options.create,
                                                    .read_only = options.read_only,
                                                    .busy_timeout_ms = options.busy_timeout_ms,
                                                    .wal = false})});
      schema = ReadFileSchema(made->connection);
    } catch (const SqliteError& e) {
      if (e.code() == kSqliteNotADatabase) {
        return Error{ErrorCode::kConflict, NotADatabase(path, bytes)};
      }
      throw;
    }
    OpenedDatabase opened = std::move(*made);
    Connection& connection = opened.connection;
    if (auto foreign = RefuseForeignFile(path, schema)) return *foreign;
    const int version = schema.version;
    opened.upgraded_from = version;
    if (version > kSchemaVersion) {
      return Error{ErrorCode::kConflict,
                   "database " + path + " has schema version " + std::to_string(version) +
                       ", newer than this pintag supports (" + std::to_string(kSchemaVersion) +
                       "); use a newer pintag"};
    }
    // Only now: a file refused above is left exactly as it was.
    if (!options.read_only) connection.execute("PRAGMA journal_mode=WAL");
    if (version == kSchemaVersion) return opened;
    if (options.read_only) {
      return Error{ErrorCode::kConflict, "database " + path + " has schema version " +
                                             std::to_string(version) + " and needs upgrading to " +
                                             std::to_string(kSchemaVersion) +
                                             "; open it read-write once"};
    }
    if (version == 0 && options.seed) {
      // Schema and seed in one transaction: all of it or none. A cache that holds the whole
      // seeded file lets each page reach the WAL once instead of spilling repeatedly.
      connection.execute("PRAGMA cache_size = -131072");  // KiB
      Transaction transaction(connection);
      const FileSchema locked = ReadFileSchema(connection);  // re-read under the write lock
      if (auto foreign = RefuseForeignFile(path, locked)) return *foreign;
      if (locked.version == 0) {
        detail::ApplyMigrations(connection, 0, kSchemaVersion);
        if (options.before_seeding) options.before_seeding();
        SeedDatabase(connection);
        opened.created = true;
      }
      transaction.commit();
      connection.execute("PRAGMA cache_size = -2000");  // SQLite's default
    } else {
      opened.created = version == 0;
    }
    MigrateTo(connection, kSchemaVersion);
    return opened;
  } catch (const SqliteError& e) {
    return detail::ToError(e);
  } catch (const std::runtime_error& e) {
    return Error{ErrorCode::kStorage, e.what()};
  }
}

}  // namespace pintag::db
