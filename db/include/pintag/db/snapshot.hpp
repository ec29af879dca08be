#pragma once
// Registry snapshots: a consistent, self-contained copy of a live database that read-only
// replicas serve. The registry version (schema version 4) is a counter that every committed
// change to pincodes, keys, offices, sort plans or tokens increases; a snapshot holds the
// version of the instant it copies, so two files with the same version hold the same registry.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "pintag/db/result.hpp"
#include "pintag/db/sqlite.hpp"

namespace pintag::db {

/// The registry version of an open database: 1 for a new file, then increasing.
Result<std::int64_t> RegistryVersion(Connection& connection);

struct SnapshotInfo {
  std::string path;                   ///< where the snapshot is
  std::int64_t registry_version = 0;  ///< the version it holds
  std::uint64_t bytes = 0;            ///< its size
};

/// Why the file at `path` must not be replaced by a snapshot, or empty: it is a live database (a
/// write-ahead log beside it), or a registry database in WAL mode, as `pintag serve` keeps its
/// --db (a snapshot is never in WAL mode). Renaming a file over a live database swaps it under
/// its open connections, whose log then corrupts the new file at the next checkpoint.
std::string LiveDatabaseAt(const std::string& path);

/// The database whose write-ahead log, shared-memory file or rollback journal `path` is (SQLite
/// names them DB-wal, DB-shm and DB-journal), or empty: `source`'s own under any name, or those
/// of an SQLite database named like it. Replacing one corrupts the database it belongs to.
std::string DatabaseOwningFile(const std::string& path, const std::string& source = {});

/// Copies the registry of `source` to `out_path`: its schema, and the rows of every table but the
/// scan log (each server keeps its own; the table is there, empty), read in one transaction, so
/// one instant's state while writers on other connections go on, and in time and room that do
/// not grow with the scan log. kStorage, nothing written, when PRAGMA quick_check finds the
/// source's copied tables or their indexes damaged (the message names it and the first two
/// findings). The copy is made in a temporary file beside `out_path` in rollback-journal mode (a
/// single file that opens read-only anywhere), fsynced and renamed into place, and the directory
/// fsynced: a reader of `out_path` sees the old file or the new one, never part of one. kStorage
/// when the directory cannot be written; the temporary file is removed on every failure. kConflict,
/// with nothing written, when `out_path` is the source database itself, any other live database (a
/// write-ahead log beside it), or a database's -wal, -shm or -journal file (DatabaseOwningFile).
/// Temporary files beside `out_path` that no process is writing (left by one killed with SIGKILL)
/// are removed: a temporary file holds a flock while it is written. The same holds for
/// InstallSnapshot. Through a symbolic link, the file it names is replaced and the link kept; a
/// device, a pipe or a directory at `out_path` is kStorage (FileReplacedBy), nothing written.
Result<SnapshotInfo> WriteSnapshot(Connection& source, const std::string& out_path);

/// Puts a snapshot received as bytes (from a primary) at `path`: written to a temporary file
/// beside it, fsynced, checked with VerifySnapshot, then renamed into place and the directory
/// fsynced. Bytes that are not a whole snapshot of the current schema are refused with
/// VerifySnapshot's error (naming `path`, not the temporary file) and `path` is left as it was;
/// kConflict, with nothing written, when `path` is a live database (LiveDatabaseAt). kConflict,
/// `path` left as it was, when `path` holds a snapshot whose keys the received one does not all
/// give to the same pincodes (a primary restored from an older backup reuses the keys it lost,
/// and labels printed with them would be misrouted).
Result<SnapshotInfo> InstallSnapshot(std::string_view bytes, const std::string& path);

/// Nothing when the snapshot at `received` gives every key of the registry at `current` to the
/// same pincode; else kConflict naming what it loses or gives to another pincode (labels printed
/// with such a key would be misrouted), or kStorage when either file cannot be read. The check
/// InstallSnapshot makes, for a replica that takes a file renamed into place (--read-only).
std::optional<Error> KeysNotKeptBy(const std::string& received, const std::string& current);

/// Removes the temporary files that WriteSnapshot and InstallSnapshot are writing at this moment.
/// For a signal handler about to end the process, which would otherwise leave them beside their
/// target (`pintag snapshot` on Ctrl-C): async-signal-safe, it only reads atomics and calls
/// unlink(). A temporary file whose path is longer than 4 KiB is not covered.
void RemoveSnapshotTemporariesOnSignal() noexcept;

/// Opens `path` read-only and checks it is a whole PinTag database of the current schema
/// (PRAGMA quick_check) and not in WAL mode; its version and size. kStorage for a damaged or
/// foreign file, kConflict for another schema version or a WAL-mode file, kNotFound when it does
/// not exist.
Result<SnapshotInfo> VerifySnapshot(const std::string& path);

}  // namespace pintag::db
