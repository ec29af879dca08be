#pragma once
// The 15-bit key a PinTag carries. The registry maps each pincode to one key.

#include <compare>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace pintag {

inline constexpr int kKeyBits = 15;
inline constexpr int kKeyCount = 1 << kKeyBits;  // 32,768 keys: 0 … 32767

/// A tag key, always in [0, kKeyCount). Check untrusted numbers with IsValid first.
class TagKey {
 public:
  constexpr TagKey() = default;
  /// Precondition: IsValid(value); the top bit of a 16-bit value is dropped.
  constexpr explicit TagKey(std::uint16_t value) : value_(value & (kKeyCount - 1)) {}

  static constexpr bool IsValid(long long value) { return value >= 0 && value < kKeyCount; }

  constexpr std::uint16_t value() const { return value_; }
  constexpr auto operator<=>(const TagKey&) const = default;

 private:
  std::uint16_t value_ = 0;
};

/// The outcome of parsing text as a key: a key, or the reason it is not one.
struct ParsedTagKey {
  std::optional<TagKey> key;
  std::string error;  ///< empty when `key` holds a value
  explicit operator bool() const { return key.has_value(); }
};

/// Accepts a decimal integer 0 … 32767 in ASCII digits, with any number of leading zeros; no
/// sign, spaces or other characters.
ParsedTagKey ParseTagKey(std::string_view text);

}  // namespace pintag
