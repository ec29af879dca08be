#pragma once
// Assigning keys to pincodes (DESIGN.md §2): multiplicative-hash start slot, linear probing over
// the 32,768 slots, append-only. Pure and deterministic, so two registries seeded from the same
// pincodes hold the same table. Lives in codec so that db and tests share one definition.

#include <bitset>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "pintag/codec/pincode.hpp"
#include "pintag/codec/tag_key.hpp"

namespace pintag {

/// First slot probed for a pincode: the top 15 bits of (pincode × 2654435761) mod 2^32.
constexpr TagKey StartSlot(Pincode pincode) {
  const auto product = static_cast<std::uint32_t>(pincode.value() * 2654435761ULL);
  return TagKey(static_cast<std::uint16_t>(product >> (32 - kKeyBits)));
}

/// Hands out keys by linear probing from each pincode's start slot. Slots already taken — live or
/// retired keys — are never handed out again.
class KeyAllocator {
 public:
  KeyAllocator() = default;
  /// Starts from a table that already holds `taken` keys (all keys ever allocated, retired too).
  explicit KeyAllocator(std::span<const TagKey> taken);

  /// The first free slot at or after StartSlot(pincode), wrapping at 32768, now marked taken;
  /// nothing when all 32,768 keys are gone.
  std::optional<TagKey> allocate(Pincode pincode);

  bool isTaken(TagKey key) const { return taken_.test(key.value()); }
  int takenCount() const { return static_cast<int>(taken_.count()); }

 private:
  std::bitset<kKeyCount> taken_;
};

/// The seeding rule: visits `pincodes` in ascending order (duplicates once) and allocates each a
/// key on an empty table. Returns (pincode, key) pairs in ascending pincode order. Fails (nullopt)
/// only when there are more than 32,768 distinct pincodes.
std::optional<std::vector<std::pair<Pincode, TagKey>>> SeedKeyTable(std::vector<Pincode> pincodes);

}  // namespace pintag
