#pragma once
// Indian postal index numbers: exactly six ASCII digits, the first 1–9.

#include <compare>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace pintag {

class Pincode {
 public:
  /// Precondition: 100000 <= value <= 999999 (use ParsePincode for untrusted text).
  constexpr explicit Pincode(std::uint32_t value) : value_(value) {}

  constexpr std::uint32_t value() const { return value_; }
  std::string str() const { return std::to_string(value_); }
  constexpr auto operator<=>(const Pincode&) const = default;

 private:
  std::uint32_t value_;
};

/// The outcome of parsing text as a pincode: a pincode, or the reason it is not one.
struct ParsedPincode {
  std::optional<Pincode> pincode;
  std::string error;  ///< empty when `pincode` holds a value
  explicit operator bool() const { return pincode.has_value(); }
};

/// Accepts exactly six ASCII digits with the first in 1–9; no signs, spaces or other characters.
ParsedPincode ParsePincode(std::string_view text);

}  // namespace pintag
