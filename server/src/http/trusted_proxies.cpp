#include "pintag/server/trusted_proxies.hpp"

#include <arpa/inet.h>

#include <algorithm>
#include <charconv>
#include <cstring>

namespace pintag::server {
namespace {

struct Address {
  bool v6 = false;
  std::array<unsigned char, 16> bytes{};
};

std::string_view Trimmed(std::string_view text) {
  const auto first = text.find_first_not_of(" \t");
  if (first == std::string_view::npos) return {};
  const auto last = text.find_last_not_of(" \t");
  return text.substr(first, last - first + 1);
}

/// The address in "1.2.3.4", "::1", "[::1]", or either with a port ("1.2.3.4:80", "[::1]:80"):
/// some proxies write one. Empty when the brackets are unbalanced.
std::string_view HostPart(std::string_view text) {
  text = Trimmed(text);
  if (!text.empty() && text.front() == '[') {
    const auto close = text.find(']');
    if (close == std::string_view::npos) return {};
    const std::string_view after = text.substr(close + 1);
    if (!after.empty() && after.front() != ':') return {};
    return text.substr(1, close - 1);
  }
  if (std::count(text.begin(), text.end(), ':') == 1) return text.substr(0, text.find(':'));
  return text;
}

/// An IPv4-mapped IPv6 address is its IPv4 address, as a dual-stack socket names it.
std::optional<Address> ParseAddress(std::string_view written) {
  const std::string_view text = HostPart(written);
  if (text.empty() || text.size() >= INET6_ADDRSTRLEN) return std::nullopt;
  const std::string zero_ended(text);
  Address address;
  if (::inet_pton(AF_INET, zero_ended.c_str(), address.bytes.data()) == 1) return address;
  if (::inet_pton(AF_INET6, zero_ended.c_str(), address.bytes.data()) != 1) return std::nullopt;
  static constexpr std::array<unsigned char, 12> kMappedPrefix = {0, 0, 0, 0, 0,    0,
                                                                  0, 0, 0, 0, 0xff, 0xff};
  if (std::equal(kMappedPrefix.begin(), kMappedPrefix.end(), address.bytes.begin())) {
    std::memmove(address.bytes.data(), address.bytes.data() + 12, 4);
    std::fill(address.bytes.begin() + 4, address.bytes.end(), 0);
    return address;
  }
  address.v6 = true;
  return address;
}

}  // namespace

std::optional<TrustedProxies> TrustedProxies::Parse(const std::vector<std::string>& specs,
                                                    std::string* error) {
  TrustedProxies proxies;
  for (const std::string& spec : specs) {
    const auto refuse = [&](const std::string& why) {
      if (error != nullptr) {
        error->assign(1, '\'');  // not = "'": GCC 12 warns falsely (its bug 105329)
        *error += spec;
        *error += "' ";
        *error += why;
      }
      return std::nullopt;
    };
    const std::string_view text = Trimmed(spec);
    const auto slash = text.find('/');
    const std::string_view host = text.substr(0, slash);
    // A port or brackets name one socket, not a proxy; only the bare address is taken here.
    if (host.find('[') != std::string_view::npos ||
        std::count(host.begin(), host.end(), ':') == 1) {
      return refuse("is not an IP address: write the address alone, without a port");
    }
    const std::optional<Address> address = ParseAddress(host);
    if (!address) return refuse("is not an IPv4 or IPv6 address (or a range such as 10.0.0.0/8)");
    // An IPv4-mapped IPv6 range ("::ffff:10.0.0.0/104") is matched as the IPv4 range it maps
    // (10.0.0.0/8): its prefix counts the 96 bits of the mapping.
    const bool mapped = !address->v6 && host.find(':') != std::string_view::npos;
    const int written_width = address->v6 || mapped ? 128 : 32;
    const int least = mapped ? 96 : 0;
    int bits = written_width;
    if (slash != std::string_view::npos) {
      const std::string_view digits = text.substr(slash + 1);
      const auto [end, failure] =
          std::from_chars(digits.data(), digits.data() + digits.size(), bits);
      if (digits.empty() || failure != std::errc() || end != digits.data() + digits.size() ||
          bits < least || bits > written_width) {
        return refuse("has a prefix length that is not a number from " + std::to_string(least) +
                      " to " + std::to_string(written_width));
      }
    }
    if (mapped) bits -= 96;
    proxies.ranges_.push_back({.v6 = address->v6, .bytes = address->bytes, .prefix_bits = bits});
  }
  return proxies;
}

bool TrustedProxies::trusts(std::string_view address_text) const {
  const std::optional<Address> address = ParseAddress(address_text);
  return address && trustsBytes(address->v6, address->bytes);
}

bool TrustedProxies::trustsBytes(bool v6, const std::array<unsigned char, 16>& bytes) const {
  return std::any_of(ranges_.begin(), ranges_.end(), [&](const Range& range) {
    if (range.v6 != v6) return false;
    const int whole_bytes = range.prefix_bits / 8;
    if (!std::equal(range.bytes.begin(), range.bytes.begin() + whole_bytes, bytes.begin())) {
      return false;
    }
    const int rest = range.prefix_bits % 8;
    if (rest == 0) return true;
    const auto mask = static_cast<unsigned char>(0xff << (8 - rest));
    return (range.bytes[whole_bytes] & mask) == (bytes[whole_bytes] & mask);
  });
}

TrustedProxies::Client TrustedProxies::clientOf(std::string_view peer,
                                                std::string_view forwarded_for) const {
  std::string_view client = peer;
  bool forwarded = false;
  bool trusted = trusts(peer);  // of the address `client` holds; each entry is parsed once
  std::string_view rest = forwarded_for;
  while (trusted && !rest.empty()) {
    const auto comma = rest.rfind(',');
    const std::string_view entry =
        Trimmed(comma == std::string_view::npos ? rest : rest.substr(comma + 1));
    rest = comma == std::string_view::npos ? std::string_view() : rest.substr(0, comma);
    if (entry.empty()) continue;  // "a, , b" or a trailing comma: nothing said there
    const std::optional<Address> address = ParseAddress(entry);
    if (!address) break;
    client = HostPart(entry);
    forwarded = true;
    trusted = trustsBytes(address->v6, address->bytes);
  }
  return {std::string(client), forwarded};
}

}  // namespace pintag::server
