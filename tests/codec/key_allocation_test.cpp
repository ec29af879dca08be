#include "pintag/codec/key_allocation.hpp"

#include <gtest/gtest.h>

#include <random>
#include <set>

namespace pintag {
namespace {

TEST(KeyAllocation, StartSlotsWorkedByHand) {
  // 110001 × 2654435761 = 291,990,588,145,761; mod 2^32 = 1,531,494,497; >> 17 = 11,684.
  EXPECT_EQ(StartSlot(Pincode(110001)).value(), 11684);
  // 400001 × 2654435761 = 1,061,776,958,835,761; mod 2^32 = 913,722,417; >> 17 = 6,971.
  EXPECT_EQ(StartSlot(Pincode(400001)).value(), 6971);
  // 560001 × 2654435761 = 1,486,486,680,595,761; mod 2^32 = 2,794,417,457; >> 17 = 21,319.
  EXPECT_EQ(StartSlot(Pincode(560001)).value(), 21319);
  // 999999 × 2654435761 = 2,654,433,106,564,239; mod 2^32 = 1,583,715,471; >> 17 = 12,082.
  EXPECT_EQ(StartSlot(Pincode(999999)).value(), 12082);
}

TEST(KeyAllocation, CollisionsProbeLinearlyInAscendingPincodeOrder) {
  // 100000, 139603 and 150549 all start at slot 13063; given out of order, they still take
  // 13063, 13064, 13065 in ascending pincode order.
  const auto table = SeedKeyTable({Pincode(150549), Pincode(100000), Pincode(139603)});
  ASSERT_TRUE(table.has_value());
  ASSERT_EQ(table->size(), 3U);
  EXPECT_EQ((*table)[0], std::pair(Pincode(100000), TagKey(13063)));
  EXPECT_EQ((*table)[1], std::pair(Pincode(139603), TagKey(13064)));
  EXPECT_EQ((*table)[2], std::pair(Pincode(150549), TagKey(13065)));
}

TEST(KeyAllocation, ProbingWrapsPastTheLastSlot) {
  // 101098 and 140701 both start at slot 32767, the last one.
  const auto table = SeedKeyTable({Pincode(140701), Pincode(101098), Pincode(101098)});
  ASSERT_TRUE(table.has_value());
  ASSERT_EQ(table->size(), 2U);  // duplicates count once
  EXPECT_EQ((*table)[0].second, TagKey(32767));
  EXPECT_EQ((*table)[1].second, TagKey(0));
}

TEST(KeyAllocation, TakenKeysAreNeverHandedOutAgain) {
  const std::vector<TagKey> taken = {TagKey(11684), TagKey(11685)};
  KeyAllocator allocator(taken);
  EXPECT_EQ(allocator.allocate(Pincode(110001)), TagKey(11686));
  EXPECT_TRUE(allocator.isTaken(TagKey(11686)));
  EXPECT_EQ(allocator.takenCount(), 3);
}

TEST(KeyAllocation, LargeSyntheticSetIsCollisionFreeAndDeterministic) {
  std::mt19937 random(20261121);
  std::set<std::uint32_t> values;
  while (values.size() < 30000) values.insert(100000 + random() % 900000);
  std::vector<Pincode> pincodes;
  pincodes.reserve(values.size());
  for (const std::uint32_t v : values) pincodes.emplace_back(v);
  std::vector<Pincode> shuffled = pincodes;
  std::shuffle(shuffled.begin(), shuffled.end(), random);

  const auto first = SeedKeyTable(pincodes);
  const auto second = SeedKeyTable(shuffled);
  ASSERT_TRUE(first && second);
  EXPECT_EQ(*first, *second);
  std::set<TagKey> keys;
  for (const auto& [pincode, key] : *first) keys.insert(key);
  EXPECT_EQ(keys.size(), pincodes.size());
}

TEST(KeyAllocation, FullTableRefusesMore) {
  KeyAllocator allocator;
  for (int i = 0; i < kKeyCount; ++i) ASSERT_TRUE(allocator.allocate(Pincode(100000 + i)));
  EXPECT_FALSE(allocator.allocate(Pincode(999999)).has_value());
  std::vector<Pincode> too_many;
  too_many.reserve(kKeyCount + 1);
  for (int i = 0; i <= kKeyCount; ++i) too_many.emplace_back(100000 + i);
  EXPECT_FALSE(SeedKeyTable(too_many).has_value());
}

}  // namespace
}  // namespace pintag
