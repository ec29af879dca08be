#pragma once
// The database a subcommand works on (`--db`, default pintag.db).

#include <string>

#include "pintag/db/sqlite.hpp"

namespace pintag::cli {

/// Opens and migrates the database at `path`; a missing file is created and seeded from the
/// bundled registry, which is said on stderr. Throws std::runtime_error when it cannot open.
db::Connection OpenDb(const std::string& path);

}  // namespace pintag::cli
