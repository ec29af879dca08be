#include "pintag/codec/key_allocation.hpp"

#include <algorithm>

namespace pintag {

KeyAllocator::KeyAllocator(std::span<const TagKey> taken) {
  for (const TagKey key : taken) taken_.set(key.value());
}

std::optional<TagKey> KeyAllocator::allocate(Pincode pincode) {
  if (taken_.all()) return std::nullopt;
  int slot = StartSlot(pincode).value();
  while (taken_.test(slot)) slot = (slot + 1) % kKeyCount;
  taken_.set(slot);
  return TagKey(static_cast<std::uint16_t>(slot));
}

std::optional<std::vector<std::pair<Pincode, TagKey>>> SeedKeyTable(std::vector<Pincode> pincodes) {
  std::sort(pincodes.begin(), pincodes.end());
  pincodes.erase(std::unique(pincodes.begin(), pincodes.end()), pincodes.end());
  if (pincodes.size() > static_cast<std::size_t>(kKeyCount)) return std::nullopt;
  KeyAllocator allocator;
  std::vector<std::pair<Pincode, TagKey>> table;
  table.reserve(pincodes.size());
  for (const Pincode pincode : pincodes) table.emplace_back(pincode, *allocator.allocate(pincode));
  return table;
}

}  // namespace pintag
