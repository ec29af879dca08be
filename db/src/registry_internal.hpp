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

/// Whether `pincode` has an office named `name`: kNone, kSame, or kRenamed when one was stored
/// under a name that differs only in spaces at either end (a database seeded before the seed was
/// trimmed has 55 such names, e.g. "New Delhi "); that office now carries `name`, so an upsert
/// that follows updates it instead of adding a second office.
enum class OfficeMatch { kNone, kSame, kRenamed };
OfficeMatch ClaimOffice(Connection& connection, Pincode pincode, const std::string& name);

/// Inserts or updates the office (pincode, office.name), claiming one stored under the name
/// with spaces at either end (ClaimOffice); returns 0 unchanged, 1 inserted, 2 updated (renamed
/// included). Absent optional fields keep what is stored.
int UpsertOffice(Connection& connection, Pincode pincode, const PostOffice& office,
                 std::string_view source);

}  // namespace pintag::db::detail
