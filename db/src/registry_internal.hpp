#pragma once
// Shared by the registry API and the importer; callers hold a transaction.

#include <optional>
#include <string>
#include <string_view>

#include "pintag/codec/key_allocation.hpp"
#include "pintag/db/registry.hpp"

namespace pintag::db::detail {

/// A KeyAllocator that knows every key ever allocated in this database (retired ones too).
KeyAllocator LoadKeyAllocator(Connection& connection);

/// Inserts an active pincode and its newly allocated key; nothing when the keys are exhausted.
std::optional<TagKey> InsertPincode(Connection& connection, KeyAllocator& allocator,
                                    Pincode pincode, std::string_view source);

/// Nothing when every text field of `office` is acceptable, else the error naming the field.
std::optional<Error> CheckOffice(const PostOffice& office);

/// The office upsert statement (parameters bound by BindOffice): inserts, or updates a stored
/// office only where a field differs, so sqlite3_changes tells "updated" from "unchanged".
const std::string& UpsertOfficeSql();
void BindOffice(Statement& upsert, Pincode pincode, const PostOffice& office,
                std::string_view source);

/// Finds `pincode`'s office named `name`. When `name` has no space at either end (the importer's
/// names never do), a stored name that differs from it only in such spaces is the same office:
/// kNone, kSame when it is stored exactly once as `name`, or kClaimed when the stored office was
/// renamed to `name`, or twins of it stored under spaced names were deleted, leaving the one
/// office (a database seeded before the seed was trimmed has 55 such names, e.g. "New Delhi ",
/// and an import then added the trimmed name beside them). An upsert that follows then updates
/// that office instead of adding another. A `name` with such spaces (the API stores text
/// verbatim) matches only itself.
enum class OfficeMatch { kNone, kSame, kClaimed };
OfficeMatch ClaimOffice(Connection& connection, Pincode pincode, const std::string& name);

/// Inserts or updates the office (pincode, office.name), claiming one stored under the name with
/// spaces at either end (ClaimOffice); returns 0 unchanged, 1 inserted, 2 updated (claimed
/// included). Absent optional fields keep what is stored.
int UpsertOffice(Connection& connection, Pincode pincode, const PostOffice& office,
                 std::string_view source);

}  // namespace pintag::db::detail
