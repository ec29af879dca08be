#pragma once
// Registry (pintag::db) errors as HTTP problems, and the registry lookups every route group makes
// the same way: a sort plan by name, a pincode that may still be printed.

#include <string>
#include <string_view>

#include "pintag/codec/pincode.hpp"
#include "pintag/db/registry.hpp"
#include "pintag/db/result.hpp"
#include "pintag/db/sort_plan.hpp"
#include "pintag/db/sqlite.hpp"

namespace pintag::app {

/// Throws the HttpError for a registry error: kInvalid 400, kNotFound 404, kConflict 409,
/// kPrecondition 412, kTooLarge 413, kUnauthorized 401, kFull 507, kBusy 503, kNoSpace 507,
/// kReadOnly 503, kStorage 500 (the last three say what failed in words; SQLite's message, which
/// names files, goes to stderr only).
[[noreturn]] void ThrowDbError(const db::Error& error, std::string title = {});

template <typename T>
T Unwrap(db::Result<T> result, std::string title = {}) {
  if (!result) ThrowDbError(result.error(), std::move(title));
  return std::move(result).value();
}
inline void Unwrap(const db::Result<void>& result, std::string title = {}) {
  if (!result) ThrowDbError(result.error(), std::move(title));
}

/// 404 "Unknown Sort Plan" with the registry's kNotFound `not_found`, which names the plan asked
/// for and a stored one that reads like it.
[[noreturn]] void ThrowUnknownPlan(const db::Error& not_found);
/// The sort plan called `name`, rules and all; 404 "Unknown Sort Plan" when there is none. For
/// the plan's own routes and for work that routes many pincodes under one version of it.
db::SortPlan LoadPlan(db::Connection& connection, std::string_view name);
/// 404 "Unknown Sort Plan" unless a plan called `name` is stored; reads none of its rules.
void RequirePlan(db::Connection& connection, std::string_view name);
/// Where `pincode` goes under the plan called `name`, read by its prefixes alone (a plan may hold
/// 100,000 rules: loading them for one pincode costs ~20 ms); 404 "Unknown Sort Plan".
db::Routing RouteUnder(db::Connection& connection, Pincode pincode, std::string_view name);

/// The record of a pincode labels may be printed for: 404 "Unknown Pincode" when the registry
/// does not hold it, 410 "Retired Pincode" when it was retired (its printed labels still decode).
db::PincodeRecord LoadActivePincode(db::Connection& connection, Pincode pincode);

}  // namespace pintag::app
