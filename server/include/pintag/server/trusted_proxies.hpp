#pragma once
// Which client a request came from when it passed through reverse proxies (nginx before the
// replicas, docs/SCALING.md): the connection's peer is then the proxy, and the client is in the
// X-Forwarded-For header the proxy appended to. A client can write that header too, so it is
// believed only as far as the proxies the operator named (`serve --trusted-proxy`).

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace pintag::server {

class TrustedProxies {
 public:
  TrustedProxies() = default;  ///< trusts no one: the client is always the peer

  /// Each spec an IPv4 or IPv6 address ("127.0.0.1", "::1") or a range in CIDR form
  /// ("10.0.0.0/8", "fd00::/8"). Nothing, with `error` saying which spec and why, when one is
  /// neither.
  static std::optional<TrustedProxies> Parse(const std::vector<std::string>& specs,
                                             std::string* error);

  bool empty() const { return ranges_.empty(); }
  /// Whether `address` (as the socket or the header writes it) is one of the proxies.
  bool trusts(std::string_view address) const;

  struct Client {
    std::string address;
    bool forwarded = false;  ///< named by a trusted proxy's header, not the connection's peer
  };
  /// The client of a request from `peer` whose X-Forwarded-For values, joined by commas, are
  /// `forwarded_for`: the peer when it is not trusted; else, walking the header from its right
  /// end, the first address that is not trusted (without a port, if the entry had one). An entry
  /// that is not an address stops the walk at the trusted hop that sent it, so the answer is
  /// always an address some trusted proxy saw. `forwarded` even when the address is the peer's
  /// own (a client on the proxy's host).
  Client clientOf(std::string_view peer, std::string_view forwarded_for) const;

 private:
  /// Whether a parsed address (network order, IPv4 in the first 4 bytes) lies in a range.
  bool trustsBytes(bool v6, const std::array<unsigned char, 16>& bytes) const;

  struct Range {
    bool v6 = false;
    std::array<unsigned char, 16> bytes{};  ///< network order; IPv4 in the first 4
    int prefix_bits = 0;
  };
  std::vector<Range> ranges_;
};

}  // namespace pintag::server
