#pragma once

#include "pintag/db/sqlite.hpp"

namespace pintag::db::detail {

/// Runs migration steps (from, target] in the caller's transaction, bumping user_version.
void ApplyMigrations(Connection& connection, int from, int target);

}  // namespace pintag::db::detail
