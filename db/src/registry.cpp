#include "pintag/db/registry.hpp"

#include <map>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "guard.hpp"
#include "pintag/db/office_fields.hpp"
#include "pintag/db/text.hpp"
#include "registry_internal.hpp"

namespace pintag::db {
namespace {

using detail::Guard;
using detail::kNowSql;

constexpr const char* kOfficeColumns =
    "o.id, o.name, o.branch_type, o.delivery, o.division, o.region, o.circle, o.district, "
    "o.state, o.taluk, o.latitude, o.longitude";
constexpr int kOfficeColumnCount = 12;

PostOffice ReadOffice(const Statement& s, int first) {
  PostOffice office;
  office.id = s.getInt64(first);
  office.name = s.getText(first + 1);
  office.branch_type = s.getOptionalText(first + 2);
  office.delivery = s.getOptionalText(first + 3);
  office.division = s.getText(first + 4);
  office.region = s.getText(first + 5);
  office.circle = s.getText(first + 6);
  office.district = s.getText(first + 7);
  office.state = s.getText(first + 8);
  office.taluk = s.getOptionalText(first + 9);
  if (!s.isNull(first + 10)) office.latitude = s.getDouble(first + 10);
  if (!s.isNull(first + 11)) office.longitude = s.getDouble(first + 11);
  return office;
}

PincodeStatus ReadStatus(const Statement& s, int column) {
  return s.getText(column) == "retired" ? PincodeStatus::kRetired : PincodeStatus::kActive;
}

/// The record for the pincode `where` selects (a condition on p or k with parameter ?1).
Result<PincodeRecord> LoadRecord(Connection& connection, const char* where, std::int64_t value,
                                 const std::string& not_found) {
  Statement head = connection.prepare(
      std::string("SELECT p.pincode, k.tag_key, p.status, p.added_at, p.retired_at, "
                  "k.allocated_at FROM pincodes p JOIN tag_keys k ON k.pincode = p.pincode "
                  "WHERE ") +
      where);
  head.bind(1, value);
  if (!head.step()) return Error{ErrorCode::kNotFound, not_found};
  PincodeRecord record;
  record.pincode = Pincode(static_cast<std::uint32_t>(head.getInt64(0)));
  record.key = TagKey(static_cast<std::uint16_t>(head.getInt64(1)));
  record.status = ReadStatus(head, 2);
  record.added_at = head.getText(3);
  record.retired_at = head.getOptionalText(4);
  record.key_allocated_at = head.getText(5);

  Statement offices = connection.prepare(std::string("SELECT ") + kOfficeColumns +
                                         " FROM offices o WHERE o.pincode = ?1 ORDER BY o.id");
  offices.bind(1, std::int64_t{record.pincode.value()});
  while (offices.step()) record.offices.push_back(ReadOffice(offices, 0));
  if (const PostOffice* main = MainOffice(record)) {
    record.district = main->district;
    record.state = main->state;
    record.circle = main->circle;
    record.region = main->region;
    record.division = main->division;
  }
  return record;
}

}  // namespace

const char* ToString(PincodeStatus status) {
  return status == PincodeStatus::kRetired ? "retired" : "active";
}

const PostOffice* MainOffice(const PincodeRecord& record) {
  for (const PostOffice& office : record.offices) {
    if (office.branch_type == "HO") return &office;
  }
  // India Post's newer layout types a sub office PO where the older typed it SO.
  for (const PostOffice& office : record.offices) {
    if (office.branch_type == "SO" || office.branch_type == "PO") return &office;
  }
  return record.offices.empty() ? nullptr : &record.offices.front();
}

Result<PincodeRecord> LookupPincode(Connection& connection, Pincode pincode) {
  return Guard([&]() -> Result<PincodeRecord> {
    return LoadRecord(connection, "p.pincode = ?1", pincode.value(),
                      "pincode " + pincode.str() + " is not in the registry");
  });
}

Result<PincodeRecord> LookupKey(Connection& connection, TagKey key) {
  return Guard([&]() -> Result<PincodeRecord> {
    return LoadRecord(connection, "k.tag_key = ?1", key.value(),
                      "key " + std::to_string(key.value()) + " is not allocated");
  });
}

Result<SearchPage> Search(Connection& connection, const SearchQuery& query) {
  if (query.name_prefix.empty() && query.district.empty() && query.state.empty()) {
    return Error{ErrorCode::kInvalid, "give an office name prefix, a district or a state"};
  }
  if (query.limit < 1 || query.limit > 500) {
    return Error{ErrorCode::kInvalid, "limit must be 1 to 500"};
  }
  if (query.offset < 0) return Error{ErrorCode::kInvalid, "offset must be >= 0"};
  for (const auto& [field, value] :
       {std::pair{"name prefix", &query.name_prefix}, std::pair{"district", &query.district},
        std::pair{"state", &query.state}}) {
    if (auto error = CheckQueryText(field, *value, kMaxNameBytes)) return *error;
  }
  return Guard([&]() -> Result<SearchPage> {
    // Fixed SQL fragments; every value is a bound parameter.
    std::string where = " WHERE 1";
    if (!query.name_prefix.empty()) {
      // A range on the NOCASE index: every name with this prefix sorts in [?1, ?1 || x'FF'), as
      // no UTF-8 text contains the byte 0xFF; the second test drops near misses.
      where +=
          " AND o.name >= ?1 COLLATE NOCASE AND o.name < (?1 || x'FF') COLLATE NOCASE"
          " AND substr(o.name, 1, length(?1)) = ?1 COLLATE NOCASE";
    }
    if (!query.district.empty()) where += " AND o.district = ?2 COLLATE NOCASE";
    if (!query.state.empty()) where += " AND o.state = ?3 COLLATE NOCASE";
    const auto bind = [&](Statement& s) {
      if (!query.name_prefix.empty()) s.bind(1, query.name_prefix);
      if (!query.district.empty()) s.bind(2, query.district);
      if (!query.state.empty()) s.bind(3, query.state);
    };
    SearchPage page;
    page.limit = query.limit;
    page.offset = query.offset;
    Statement count = connection.prepare("SELECT count(*) FROM offices o" + where);
    bind(count);
    count.step();
    page.total = count.getInt64(0);

    Statement rows = connection.prepare(
        std::string("SELECT ") + kOfficeColumns +
        ", o.pincode, k.tag_key, p.status FROM offices o JOIN pincodes p ON p.pincode = "
        "o.pincode JOIN tag_keys k ON k.pincode = o.pincode" +
        where + " ORDER BY o.name COLLATE NOCASE, o.pincode, o.id LIMIT ?4 OFFSET ?5");
    bind(rows);
    rows.bind(4, query.limit).bind(5, query.offset);
    while (rows.step()) {
      OfficeHit hit;
      hit.office = ReadOffice(rows, 0);
      hit.pincode = Pincode(static_cast<std::uint32_t>(rows.getInt64(kOfficeColumnCount)));
      hit.key = TagKey(static_cast<std::uint16_t>(rows.getInt64(kOfficeColumnCount + 1)));
      hit.status = ReadStatus(rows, kOfficeColumnCount + 2);
      page.hits.push_back(std::move(hit));
    }
    return page;
  });
}

Result<RegistryCounts> CountRegistry(Connection& connection) {
  return Guard([&]() -> Result<RegistryCounts> {
    Statement s = connection.prepare(
        "SELECT (SELECT count(*) FROM pincodes WHERE status = 'active'),"
        " (SELECT count(*) FROM pincodes WHERE status = 'retired'),"
        " (SELECT count(*) FROM offices), (SELECT count(*) FROM tag_keys),"
        " (SELECT count(*) FROM sort_plans),"
        " (SELECT count(*) FROM api_tokens WHERE revoked_at IS NULL),"
        " (SELECT count(*) FROM scan_log)");
    s.step();
    RegistryCounts counts;
    counts.pincodes_active = s.getInt64(0);
    counts.pincodes_retired = s.getInt64(1);
    counts.offices = s.getInt64(2);
    counts.keys_allocated = s.getInt64(3);
    counts.keys_free = kKeyCount - counts.keys_allocated;
    counts.sort_plans = s.getInt64(4);
    counts.tokens_active = s.getInt64(5);
    counts.scans = s.getInt64(6);
    return counts;
  });
}

namespace {

/// Offices `first` and `second` (0-based) of one request name one office.
Error OfficesNamedAlike(std::size_t first, std::size_t second, std::string_view first_name,
                        std::string_view second_name) {
  std::string message =
      "offices " + std::to_string(first + 1) + " and " + std::to_string(second + 1);
  if (first_name == second_name) {
    message += " are both named '" + std::string(first_name) + "'";
  } else {
    message += " are named alike ('" + std::string(first_name) + "' and '" +
               std::string(second_name) + "' are the same letters in other Unicode code points)";
  }
  message += "; give each office of a pincode once";
  return Error{ErrorCode::kInvalid, std::move(message)};
}

}  // namespace

Result<PincodeRecord> AddPincode(Connection& connection, Pincode pincode,
                                 const std::vector<PostOffice>& offices) {
  for (std::size_t i = 0; i < offices.size(); ++i) {
    if (auto error = detail::CheckOffice(offices[i])) {
      error->message = "office " + std::to_string(i + 1) + ": " + error->message;
      return *error;
    }
  }
  // A name is shown on labels and chosen by clerks, so it may hold no invisible character but a
  // space between words ('Janpath' + U+200B was stored beside 'Janpath' and printed as the
  // head office). The import takes India Post's file as it is; a name typed here is held to
  // what a plan name is.
  for (std::size_t i = 0; i < offices.size(); ++i) {
    if (auto error = CheckShownName("office name", TrimSpaces(offices[i].name), kMaxNameBytes)) {
      error->message = "office " + std::to_string(i + 1) + ": " + error->message;
      return *error;
    }
  }
  // A name is one office of a pincode (compared without the spaces at either end, as stored
  // offices are matched, and in one Unicode form): two entries under it would be merged into one
  // mixing both, or shown as two offices that read alike.
  std::map<std::string, std::size_t> first_named;
  for (std::size_t i = 0; i < offices.size(); ++i) {
    const std::string_view name = TrimSpaces(offices[i].name);
    const auto [first, inserted] = first_named.try_emplace(CanonicalForm(name), i);
    if (inserted) continue;
    return OfficesNamedAlike(first->second, i, TrimSpaces(offices[first->second].name), name);
  }
  return Guard([&]() -> Result<PincodeRecord> {
    Transaction transaction(connection);
    Statement exists = connection.prepare(
        "SELECT p.status, k.tag_key FROM pincodes p JOIN tag_keys k ON k.pincode = p.pincode "
        "WHERE p.pincode = ?1");
    exists.bind(1, std::int64_t{pincode.value()});
    if (exists.step()) {
      return Error{ErrorCode::kConflict, "pincode " + pincode.str() + " already exists (" +
                                             exists.getText(0) + ", key " +
                                             std::to_string(exists.getInt64(1)) + ")"};
    }
    KeyAllocator allocator = detail::LoadKeyAllocator(connection);
    if (!detail::InsertPincode(connection, allocator, pincode, "api")) {
      return Error{ErrorCode::kFull, "all 32768 keys are allocated"};
    }
    for (const PostOffice& office : offices)
      detail::UpsertOffice(connection, pincode, office, "api");
    transaction.commit();
    return LookupPincode(connection, pincode);
  });
}

Result<PincodeRecord> RetirePincode(Connection& connection, Pincode pincode) {
  return Guard([&]() -> Result<PincodeRecord> {
    Statement retire = connection.prepare(std::string("UPDATE pincodes SET status = 'retired', "
                                                      "retired_at = ") +
                                          kNowSql + " WHERE pincode = ?1 AND status = 'active'");
    retire.bind(1, std::int64_t{pincode.value()}).run();
    return LookupPincode(connection, pincode);
  });
}

Result<std::vector<KeyRow>> ListKeys(Connection& connection) {
  return Guard([&]() -> Result<std::vector<KeyRow>> {
    Statement s = connection.prepare(
        "SELECT p.pincode, k.tag_key, p.status FROM pincodes p JOIN tag_keys k ON k.pincode = "
        "p.pincode ORDER BY p.pincode");
    std::vector<KeyRow> rows;
    while (s.step()) {
      rows.push_back({Pincode(static_cast<std::uint32_t>(s.getInt64(0))),
                      TagKey(static_cast<std::uint16_t>(s.getInt64(1))), ReadStatus(s, 2)});
    }
    return rows;
  });
}

namespace detail {

KeyAllocator LoadKeyAllocator(Connection& connection) {
  std::vector<TagKey> taken;
  Statement s = connection.prepare("SELECT tag_key FROM tag_keys");
  while (s.step()) taken.emplace_back(static_cast<std::uint16_t>(s.getInt64(0)));
  return KeyAllocator(taken);
}

std::optional<TagKey> InsertPincode(Connection& connection, KeyAllocator& allocator,
                                    Pincode pincode, std::string_view source) {
  const std::optional<TagKey> key = allocator.allocate(pincode);
  if (!key) return std::nullopt;
  connection
      .prepare(std::string("INSERT INTO pincodes (pincode, status, added_at, source) VALUES "
                           "(?1, 'active', ") +
               kNowSql + ", ?2)")
      .bind(1, std::int64_t{pincode.value()})
      .bind(2, source)
      .run();
  connection
      .prepare(
          std::string("INSERT INTO tag_keys (pincode, tag_key, allocated_at) VALUES (?1, ?2, ") +
          kNowSql + ")")
      .bind(1, std::int64_t{pincode.value()})
      .bind(2, int{key->value()})
      .run();
  return key;
}

std::optional<Error> CheckOffice(const PostOffice& office) {
  const std::pair<const char*, const std::string*> required[] = {
      {"office name", &office.name}, {"division", &office.division}, {"region", &office.region},
      {"circle", &office.circle},    {"district", &office.district}, {"state", &office.state}};
  for (const auto& [field, value] : required) {
    if (auto error = CheckText(field, *value, kMaxNameBytes)) return error;
    // Stored, India Post's "unknown" would print on labels as a place ("NA, NA").
    if (MeansUnknown(TrimUnicodeSpaces(*value))) {
      return Error{ErrorCode::kInvalid, std::string(field) + " is '" + *value +
                                            "', which means unknown; it is required"};
    }
  }
  const std::pair<const char*, const std::optional<std::string>*> optional[] = {
      {"branch type", &office.branch_type},
      {"delivery", &office.delivery},
      {"taluk", &office.taluk}};
  for (const auto& [field, value] : optional) {
    if (*value) {
      if (auto error = CheckText(field, **value, kMaxNameBytes)) return error;
    }
  }
  if (office.latitude && !(*office.latitude >= -90 && *office.latitude <= 90)) {
    return Error{ErrorCode::kInvalid, "latitude must be -90 to 90"};
  }
  if (office.longitude && !(*office.longitude >= -180 && *office.longitude <= 180)) {
    return Error{ErrorCode::kInvalid, "longitude must be -180 to 180"};
  }
  return std::nullopt;
}

const std::string& UpsertOfficeSql() {
  static const std::string sql =
      "INSERT INTO offices (pincode, name, branch_type, delivery, division, region, circle, "
      "district, state, taluk, latitude, longitude, source, updated_at) VALUES (?1, ?2, ?3, ?4, "
      "?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, " +
      std::string(kNowSql) +
      ") ON CONFLICT (pincode, name) DO UPDATE SET"
      " branch_type = coalesce(excluded.branch_type, branch_type),"
      " delivery = coalesce(excluded.delivery, delivery), division = excluded.division,"
      " region = excluded.region, circle = excluded.circle, district = excluded.district,"
      " state = excluded.state, taluk = coalesce(excluded.taluk, taluk),"
      " latitude = coalesce(excluded.latitude, latitude),"
      " longitude = coalesce(excluded.longitude, longitude), source = excluded.source,"
      " updated_at = excluded.updated_at"
      " WHERE (coalesce(excluded.branch_type, branch_type), coalesce(excluded.delivery, delivery),"
      " excluded.division, excluded.region, excluded.circle, excluded.district, excluded.state,"
      " coalesce(excluded.taluk, taluk), coalesce(excluded.latitude, latitude),"
      " coalesce(excluded.longitude, longitude)) IS NOT (branch_type, delivery, division, region,"
      " circle, district, state, taluk, latitude, longitude)";
  return sql;
}

void BindOffice(Statement& upsert, Pincode pincode, const PostOffice& office,
                std::string_view source) {
  upsert.bind(1, std::int64_t{pincode.value()})
      .bind(2, office.name)
      .bind(3, office.branch_type)
      .bind(4, office.delivery)
      .bind(5, office.division)
      .bind(6, office.region)
      .bind(7, office.circle)
      .bind(8, office.district)
      .bind(9, office.state)
      .bind(10, office.taluk)
      .bind(11, office.latitude)
      .bind(12, office.longitude)
      .bind(13, source);
}

OfficeMatch ClaimOffice(Connection& connection, Pincode pincode, const std::string& name) {
  // Only a trimmed name claims others: the API stores text verbatim, so "Main " posted there stays
  // itself, and no office is ever renamed towards spaces.
  const bool trimmed = name == TrimSpaces(name);
  // SQLite's trim() drops spaces only, as TrimSpaces does. A pincode has at most a few dozen
  // offices, all reached through the (pincode, name) index; the exact name sorts first.
  std::vector<std::pair<std::int64_t, bool>> twins;  // id, exactly `name`
  {
    Statement find = connection.prepare(
        trimmed ? "SELECT id, name = ?2 FROM offices WHERE pincode = ?1 AND trim(name) = ?2 "
                  "ORDER BY name = ?2 DESC, id"
                : "SELECT id, 1 FROM offices WHERE pincode = ?1 AND name = ?2");
    find.bind(1, std::int64_t{pincode.value()}).bind(2, name);
    while (find.step()) twins.emplace_back(find.getInt64(0), find.getInt64(1) != 0);
  }
  if (twins.empty()) return OfficeMatch::kNone;
  if (twins.size() == 1 && twins[0].second) return OfficeMatch::kSame;
  // The first keeps the office (renamed unless it is exact); the rest are the same office stored
  // again under a spaced name, by an import before imports matched them: folded into it.
  if (!twins[0].second) {
    connection
        .prepare(std::string("UPDATE offices SET name = ?2, updated_at = ") + kNowSql +
                 " WHERE id = ?1")
        .bind(1, twins[0].first)
        .bind(2, name)
        .run();
  }
  for (std::size_t i = 1; i < twins.size(); ++i) {
    connection.prepare("DELETE FROM offices WHERE id = ?1").bind(1, twins[i].first).run();
  }
  return OfficeMatch::kClaimed;
}

int UpsertOffice(Connection& connection, Pincode pincode, const PostOffice& office,
                 std::string_view source) {
  const OfficeMatch match = ClaimOffice(connection, pincode, office.name);
  Statement upsert = connection.prepare(UpsertOfficeSql());
  BindOffice(upsert, pincode, office, source);
  const int changed = upsert.run();
  if (match == OfficeMatch::kNone) return 1;
  return changed > 0 || match == OfficeMatch::kClaimed ? 2 : 0;
}

}  // namespace detail
}  // namespace pintag::db
