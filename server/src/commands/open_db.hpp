#pragma once
// The database a subcommand works on (`--db`, default pintag.db).

#include <string>

#include "pintag/db/sqlite.hpp"

namespace pintag::cli {

/// Opens and migrates the database at `path`; a missing file is created and seeded from the
/// bundled registry, which is said on stderr. Throws std::runtime_error when it cannot open.
db::Connection OpenDb(const std::string& path);

/// Opens and migrates the database at `path`, which must exist: for commands that only make sense
/// on a registry in use (listing or revoking its tokens), where a mistyped path must not create
/// and seed a new one. Throws std::runtime_error naming the path when it is missing.
db::Connection OpenExistingDb(const std::string& path);

}  // namespace pintag::cli
