#include "pintag/db/database.hpp"

#include <filesystem>
#include <string>

#include "guard.hpp"
#include "schema.hpp"

namespace pintag::db {

Result<OpenedDatabase> OpenDatabase(const std::string& path, const OpenOptions& options) {
  try {
    std::error_code ignored;
    if (!options.create && !std::filesystem::exists(path, ignored)) {
      return Error{ErrorCode::kNotFound, "database " + path + " does not exist"};
    }
    OpenedDatabase opened{Connection(path, {.create = options.create,
                                            .read_only = options.read_only,
                                            .busy_timeout_ms = options.busy_timeout_ms})};
    Connection& connection = opened.connection;
    const int version = SchemaVersion(connection);
    opened.upgraded_from = version;
    if (version > kSchemaVersion) {
      return Error{ErrorCode::kConflict,
                   "database " + path + " has schema version " + std::to_string(version) +
                       ", newer than this pintag supports (" + std::to_string(kSchemaVersion) +
                       "); use a newer pintag"};
    }
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
      if (SchemaVersion(connection) == 0) {  // re-checked under the write lock
        detail::ApplyMigrations(connection, 0, kSchemaVersion);
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
