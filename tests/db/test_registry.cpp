// Lookups, search with paging, counts, adding and retiring pincodes.

#include <gtest/gtest.h>

#include <set>

#include "db_test_util.hpp"
#include "pintag/codec/key_allocation.hpp"
#include "pintag/db/registry.hpp"

namespace pintag::db {
namespace {

using test::TempDir;

class Registry : public ::testing::Test {
 protected:
  TempDir dir_;
  Connection db_ = test::OpenExisting(test::CopyOfSeeded(dir_));
};

TEST_F(Registry, LooksUpAPincodeWithItsOffices) {
  const auto record = LookupPincode(db_, Pincode(110001));
  ASSERT_TRUE(record.ok()) << record.error().message;
  EXPECT_EQ(record->status, PincodeStatus::kActive);
  EXPECT_EQ(record->district, "Central Delhi");
  EXPECT_EQ(record->state, "Delhi");
  EXPECT_EQ(record->circle, "Delhi");
  EXPECT_EQ(record->region, "Delhi");
  EXPECT_EQ(record->division, "New Delhi Central");
  EXPECT_EQ(record->offices.size(), 21u);
  EXPECT_EQ(record->offices.front().name, "Bengali Market");
  EXPECT_FALSE(record->offices.front().branch_type.has_value());  // not in the seed

  const auto by_key = LookupKey(db_, record->key);
  ASSERT_TRUE(by_key.ok());
  EXPECT_EQ(by_key->pincode, Pincode(110001));
  EXPECT_EQ(by_key->offices.size(), 21u);
}

TEST_F(Registry, UnknownPincodeAndUnallocatedKeyAreNotFound) {
  const auto pincode = LookupPincode(db_, Pincode(999999));
  ASSERT_FALSE(pincode.ok());
  EXPECT_EQ(pincode.error().code, ErrorCode::kNotFound);
  const auto rows = ListKeys(db_).value();
  std::set<int> taken;
  for (const KeyRow& row : rows) taken.insert(row.key.value());
  int free_key = 0;
  while (taken.count(free_key)) ++free_key;
  const auto key = LookupKey(db_, TagKey(static_cast<std::uint16_t>(free_key)));
  ASSERT_FALSE(key.ok());
  EXPECT_EQ(key.error().code, ErrorCode::kNotFound);
}

TEST_F(Registry, SearchesByNamePrefixDistrictAndStateWithPaging) {
  const auto page = Search(db_, {.name_prefix = "connaught", .limit = 10});
  ASSERT_TRUE(page.ok()) << page.error().message;
  ASSERT_GE(page->total, 1);
  for (const OfficeHit& hit : page->hits) {
    EXPECT_TRUE(hit.office.name.starts_with("Connaught")) << hit.office.name;
  }
  // District: all pages together hold every match exactly once.
  const auto first = Search(db_, {.district = "central delhi", .limit = 7});
  ASSERT_TRUE(first.ok());
  ASSERT_GT(first->total, 7);
  std::set<std::int64_t> ids;
  for (int offset = 0; offset < first->total; offset += 7) {
    const auto p = Search(db_, {.district = "Central Delhi", .limit = 7, .offset = offset});
    ASSERT_TRUE(p.ok());
    EXPECT_EQ(p->total, first->total);
    for (const OfficeHit& hit : p->hits) {
      EXPECT_EQ(hit.office.district, "Central Delhi");
      EXPECT_TRUE(ids.insert(hit.office.id).second);
    }
  }
  EXPECT_EQ(static_cast<std::int64_t>(ids.size()), first->total);
  // Combined filters narrow the match.
  const auto both = Search(db_, {.name_prefix = "A", .state = "Goa", .limit = 500});
  ASSERT_TRUE(both.ok());
  EXPECT_GT(both->total, 0);
  for (const OfficeHit& hit : both->hits) {
    EXPECT_EQ(hit.office.state, "Goa");
    EXPECT_TRUE(hit.office.name.starts_with("A") || hit.office.name.starts_with("a"));
  }
  EXPECT_EQ(Search(db_, {}).error().code, ErrorCode::kInvalid);
  EXPECT_EQ(Search(db_, {.state = "Goa", .limit = 0}).error().code, ErrorCode::kInvalid);
  EXPECT_EQ(Search(db_, {.state = "Goa", .offset = -1}).error().code, ErrorCode::kInvalid);
}

TEST_F(Registry, RetiringAndAddingKeepEveryEarlierKey) {
  const auto before = ListKeys(db_).value();
  const auto retired = RetirePincode(db_, Pincode(110001));
  ASSERT_TRUE(retired.ok()) << retired.error().message;
  EXPECT_EQ(retired->status, PincodeStatus::kRetired);
  EXPECT_TRUE(retired->retired_at.has_value());
  // A retired key still decodes to its pincode.
  const auto by_key = LookupKey(db_, retired->key);
  ASSERT_TRUE(by_key.ok());
  EXPECT_EQ(by_key->status, PincodeStatus::kRetired);

  std::vector<TagKey> taken;
  taken.reserve(before.size());
  for (const KeyRow& row : before) taken.push_back(row.key);
  KeyAllocator expected(taken);
  PostOffice office{.name = "Field Post Office",
                    .branch_type = "SO",
                    .division = "APS",
                    .region = "APS",
                    .circle = "Army Postal Service",
                    .district = "APS",
                    .state = "APS"};
  const auto added = AddPincode(db_, Pincode(999001), {office});
  ASSERT_TRUE(added.ok()) << added.error().message;
  EXPECT_EQ(added->key, *expected.allocate(Pincode(999001)));
  EXPECT_EQ(added->offices.size(), 1u);
  EXPECT_EQ(added->district, "APS");
  const auto added2 = AddPincode(db_, Pincode(999002));
  ASSERT_TRUE(added2.ok());
  EXPECT_EQ(added2->key, *expected.allocate(Pincode(999002)));

  const auto after = ListKeys(db_).value();
  ASSERT_EQ(after.size(), before.size() + 2);
  std::size_t j = 0;
  for (const KeyRow& row : after) {
    if (row.pincode == Pincode(999001) || row.pincode == Pincode(999002)) continue;
    ASSERT_EQ(row.pincode, before[j].pincode);
    ASSERT_EQ(row.key, before[j].key);
    ++j;
  }
  EXPECT_EQ(j, before.size());

  // Existing pincodes, retired ones too, are never re-keyed.
  EXPECT_EQ(AddPincode(db_, Pincode(110001)).error().code, ErrorCode::kConflict);
  EXPECT_EQ(AddPincode(db_, Pincode(110002)).error().code, ErrorCode::kConflict);
  // Retiring twice is a no-op; the table itself refuses edits.
  EXPECT_TRUE(RetirePincode(db_, Pincode(110001)).ok());
  EXPECT_EQ(RetirePincode(db_, Pincode(999999)).error().code, ErrorCode::kNotFound);
  EXPECT_THROW(db_.execute("UPDATE tag_keys SET tag_key = 0 WHERE pincode = 110001"), SqliteError);
  EXPECT_THROW(db_.execute("DELETE FROM tag_keys WHERE pincode = 110001"), SqliteError);

  const auto counts = CountRegistry(db_).value();
  EXPECT_EQ(counts.pincodes_active, 19159 - 1 + 2);
  EXPECT_EQ(counts.pincodes_retired, 1);
  EXPECT_EQ(counts.keys_allocated, 19161);
  EXPECT_EQ(counts.offices, 154875);
}

TEST_F(Registry, AFullDiskAndAReadOnlyFileAreToldApartFromOtherFailures) {
  // SQLite says SQLITE_FULL when a write finds no room: the disk, or (here, the same code path)
  // the page limit of this connection, set at the file's current size.
  const std::int64_t pages = db_.queryInt64("PRAGMA page_count");
  db_.queryInt64("PRAGMA max_page_count = " + std::to_string(pages));
  std::vector<PostOffice> offices(1);
  offices[0].name = std::string(60, 'x');
  offices[0].district = "D";
  offices[0].state = "S";
  offices[0].circle = "C";
  offices[0].region = "R";
  offices[0].division = "V";
  // Added until one finds no room (a few pages: each pincode and office adds rows).
  Result<PincodeRecord> added = AddPincode(db_, Pincode(999000), offices);
  for (std::uint32_t pin = 999001; pin < 999400 && added.ok(); ++pin) {
    added = AddPincode(db_, Pincode(pin), offices);
  }
  ASSERT_FALSE(added.ok());
  EXPECT_EQ(added.error().code, ErrorCode::kNoSpace) << added.error().message;
  EXPECT_EQ(std::string(ToString(added.error().code)), "no_space");

  // A read-only connection's write: SQLITE_READONLY.
  ConnectionOptions read_only;
  read_only.create = false;
  read_only.read_only = true;
  Connection reader(db_.path(), read_only);
  const auto refused = AddPincode(reader, Pincode(999999));
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, ErrorCode::kReadOnly) << refused.error().message;
}

TEST_F(Registry, AddRejectsBadOfficeText) {
  for (const std::string name : {"", "   ", "bad\x01name"}) {
    PostOffice office{
        .name = name, .division = "d", .region = "r", .circle = "c", .district = "d", .state = "s"};
    const auto added = AddPincode(db_, Pincode(999003), {office});
    ASSERT_FALSE(added.ok()) << "'" << name << "'";
    EXPECT_EQ(added.error().code, ErrorCode::kInvalid);
    EXPECT_NE(added.error().message.find("office name"), std::string::npos)
        << added.error().message;
    EXPECT_EQ(LookupPincode(db_, Pincode(999003)).error().code, ErrorCode::kNotFound);
  }
}

}  // namespace
}  // namespace pintag::db
