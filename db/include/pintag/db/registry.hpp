#pragma once
// The pincode registry and its key table: lookups, search, counts, adding and retiring pincodes.
// Every function takes the caller's Connection (one per thread, see sqlite.hpp) and returns a
// value or an Error; none throws for bad input or a busy database.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "pintag/codec/pincode.hpp"
#include "pintag/codec/tag_key.hpp"
#include "pintag/db/result.hpp"
#include "pintag/db/sqlite.hpp"

namespace pintag::db {

enum class PincodeStatus { kActive, kRetired };
const char* ToString(PincodeStatus status);  ///< "active" / "retired"

/// One post office. Text is as published (the seed keeps the package's spelling and spacing).
struct PostOffice {
  std::int64_t id = 0;  ///< row id; ignored on input
  std::string name;
  std::optional<std::string> branch_type;  ///< "HO", "SO", "BO", ... when known (not in the seed)
  std::optional<std::string> delivery;     ///< "Delivery" / "Non-Delivery" when known
  std::string division;
  std::string region;
  std::string circle;
  std::string district;
  std::string state;
  std::optional<std::string> taluk;  ///< older India Post layout only
  std::optional<double> latitude;    ///< degrees, newer India Post layout only
  std::optional<double> longitude;   ///< degrees
};

/// A pincode with its key and offices. The summary fields (district, ...) are those of its main
/// office (MainOffice); a pincode's offices can span districts, so `offices` has the detail.
struct PincodeRecord {
  Pincode pincode{100000};
  TagKey key;
  PincodeStatus status = PincodeStatus::kActive;
  std::string district, state, circle, region, division;  ///< "" when it has no offices
  std::vector<PostOffice> offices;                        ///< by id
  std::string added_at;                                   ///< ISO 8601 UTC
  std::optional<std::string> retired_at;
  std::string key_allocated_at;
};

/// The office that stands for a pincode (its summary, the office a label prints by default): the
/// head office, else a sub office (SO, or PO as the newer layout types it), else the first
/// (lowest id); nullptr when it has none.
const PostOffice* MainOffice(const PincodeRecord& record);

/// kNotFound when the pincode is not in the registry.
Result<PincodeRecord> LookupPincode(Connection& connection, Pincode pincode);
/// The pincode holding `key`, retired ones included (printed labels keep decoding). kNotFound
/// when the key was never allocated.
Result<PincodeRecord> LookupKey(Connection& connection, TagKey key);

/// Office search. Empty fields are ignored; at least one must be given. All matches are
/// case-insensitive for ASCII letters only (SQLite NOCASE); non-ASCII text matches exactly.
struct SearchQuery {
  std::string name_prefix;  ///< office name starts with this
  std::string district;     ///< district equals this
  std::string state;        ///< state equals this
  int limit = 50;           ///< page size, 1–500
  int offset = 0;           ///< rows to skip, >= 0
};

struct OfficeHit {
  Pincode pincode{100000};
  TagKey key;
  PincodeStatus status = PincodeStatus::kActive;
  PostOffice office;
};

struct SearchPage {
  std::vector<OfficeHit> hits;  ///< ordered by office name, then pincode
  std::int64_t total = 0;       ///< all matches, ignoring limit and offset
  int limit = 0;
  int offset = 0;
};

Result<SearchPage> Search(Connection& connection, const SearchQuery& query);

struct RegistryCounts {
  std::int64_t pincodes_active = 0;
  std::int64_t pincodes_retired = 0;
  std::int64_t offices = 0;
  std::int64_t keys_allocated = 0;  ///< == active + retired
  std::int64_t keys_free = 0;       ///< 32,768 − allocated
  std::int64_t sort_plans = 0;
  std::int64_t tokens_active = 0;
  std::int64_t scans = 0;
};

Result<RegistryCounts> CountRegistry(Connection& connection);

/// Adds a pincode with the next key its probe sequence finds free (DESIGN.md §2) and the given
/// offices (may be empty). kConflict when it exists (retired too: a pincode is never re-keyed),
/// kFull when no key is left, kInvalid for bad office text or two offices of one name (compared
/// without the spaces at either end).
Result<PincodeRecord> AddPincode(Connection& connection, Pincode pincode,
                                 const std::vector<PostOffice>& offices = {});

/// Marks a pincode retired; it keeps its key and offices. Retiring a retired pincode is a no-op.
Result<PincodeRecord> RetirePincode(Connection& connection, Pincode pincode);

struct KeyRow {
  Pincode pincode{100000};
  TagKey key;
  PincodeStatus status = PincodeStatus::kActive;
};

/// The whole key table, ascending by pincode.
Result<std::vector<KeyRow>> ListKeys(Connection& connection);

}  // namespace pintag::db
