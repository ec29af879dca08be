#pragma once

#include "pintag/db/sqlite.hpp"

namespace pintag::db::detail {

/// Saves the plan "default" (one bin per first two digits present in `pincodes`, fallback
/// "manual") in the caller's transaction, replacing any plan of that name.
void InsertDefaultPlan(Connection& connection);

}  // namespace pintag::db::detail
