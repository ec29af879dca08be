#pragma once
// The database a subcommand works on (`--db`, default pintag.db).

#include <functional>
#include <string>

#include "pintag/db/result.hpp"
#include "pintag/db/sqlite.hpp"

namespace pintag::cli {

/// What to say when the database at `path` stayed locked by another writer for SQLite's busy
/// timeout (an import, a serving primary's write): SQLite's own "database is locked" reads as if
/// the file were at fault. `not_done` says what was left undone ("no token was made").
std::string LockedMessage(const std::string& path, const std::string& not_done);

/// Where OpenDb says that it seeded a database: stderr for the commands, the server log for
/// `serve` (whose stderr is one log line per line, JSON with --log-format json).
using SayFunction = std::function<void(const std::string&)>;

/// Opens and migrates the database at `path`; a missing (or empty) file is created and seeded
/// from the bundled registry, which is said through `say` (stderr when empty). Throws
/// std::runtime_error when it cannot open.
db::Connection OpenDb(const std::string& path, const SayFunction& say = {});

/// Opens and migrates the database at `path`, which must exist: for commands that only make sense
/// on a registry in use (listing or revoking its tokens), where a mistyped path must not create
/// and seed a new one. Throws std::runtime_error naming the path when it is missing.
db::Connection OpenExistingDb(const std::string& path);

/// For commands that only read (keys lookup and export, token list): as OpenDb, or OpenExistingDb
/// when `must_exist`, except that a file that is not a live registry (a replica's snapshot, which
/// keeps a rollback journal) is opened read-only and left as it is. Opened to be written, it was
/// switched to WAL mode, and a replica then refused it as no snapshot.
db::Connection OpenForReading(const std::string& path, bool must_exist = false);

/// What to say when a write to the database at `path` failed in the database itself (a file or
/// directory this user cannot write, a full disk, another SQLite failure), with what was left
/// undone: SQLite's "step: attempt to write a readonly database" named no file, and an import
/// put the CSV's name before it, as if the CSV were at fault. Empty for any other error, which
/// is about the input and said in its own words.
std::string DatabaseWriteFailure(const std::string& path, const db::Error& error,
                                 const std::string& not_done);

}  // namespace pintag::cli
