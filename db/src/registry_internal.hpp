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

/// Inserts or updates the office (pincode, office.name); returns 0 unchanged, 1 inserted,
/// 2 updated. Absent optional fields keep what is stored.
int UpsertOffice(Connection& connection, Pincode pincode, const PostOffice& office,
                 std::string_view source);

}  // namespace pintag::db::detail
