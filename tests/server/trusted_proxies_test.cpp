#include "pintag/server/trusted_proxies.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace pintag::server {
namespace {

TrustedProxies Trusting(const std::vector<std::string>& specs) {
  std::string error;
  const auto proxies = TrustedProxies::Parse(specs, &error);
  EXPECT_TRUE(proxies) << error;
  return proxies.value_or(TrustedProxies());
}

TEST(TrustedProxies, RangesMatchTheirPrefixAndNothingElse) {
  const TrustedProxies proxies =
      Trusting({"10.0.0.0/8", "192.168.1.7", "fd00::/8", "172.16.0.0/12"});
  EXPECT_TRUE(proxies.trusts("10.255.1.2"));
  EXPECT_FALSE(proxies.trusts("11.0.0.1"));
  EXPECT_TRUE(proxies.trusts("192.168.1.7"));
  EXPECT_FALSE(proxies.trusts("192.168.1.8"));
  EXPECT_TRUE(proxies.trusts("fd12:3456::1"));
  EXPECT_FALSE(proxies.trusts("fe80::1"));
  // A prefix that is not a whole number of bytes: 172.16.0.0/12 is 172.16.x.x to 172.31.x.x.
  EXPECT_TRUE(proxies.trusts("172.31.255.255"));
  EXPECT_FALSE(proxies.trusts("172.32.0.1"));
  EXPECT_FALSE(proxies.trusts("172.15.255.255"));
  // An IPv4 range is not an IPv6 one of the same bytes, but a dual-stack socket's IPv4-mapped
  // name of a trusted IPv4 address is that address.
  EXPECT_FALSE(proxies.trusts("a00::1"));
  EXPECT_TRUE(proxies.trusts("::ffff:10.1.2.3"));
  EXPECT_FALSE(proxies.trusts("not an address"));
  EXPECT_FALSE(proxies.trusts(""));
  EXPECT_FALSE(TrustedProxies().trusts("127.0.0.1"));
  EXPECT_TRUE(Trusting({"0.0.0.0/0"}).trusts("8.8.8.8"));
  // An IPv4-mapped range counts the mapping's 96 bits in its prefix.
  const TrustedProxies mapped = Trusting({"::ffff:10.0.0.0/104"});
  EXPECT_TRUE(mapped.trusts("10.9.9.9"));
  EXPECT_FALSE(mapped.trusts("11.0.0.1"));
}

TEST(TrustedProxies, SpecsThatAreNotAddressesAreRefusedByName) {
  for (const std::string& bad : std::vector<std::string>{
           "", "nginx", "10.0.0.0/33", "10.0.0.0/", "10.0.0.0/8x", "10.0.0.0/-1", "::1/129",
           "::ffff:10.0.0.0/8", "1.2.3.4:80", "[::1]", "1.2.3"}) {
    std::string error;
    EXPECT_FALSE(TrustedProxies::Parse({"127.0.0.1", bad}, &error)) << bad;
    EXPECT_NE(error.find("'" + bad + "'"), std::string::npos) << error;
  }
}

/// The client's address, and "+" when a proxy's header named it.
std::string Address(const TrustedProxies& proxies, std::string_view peer,
                    std::string_view forwarded_for) {
  const TrustedProxies::Client client = proxies.clientOf(peer, forwarded_for);
  return client.address + (client.forwarded ? "+" : "");
}

TEST(TrustedProxies, TheClientIsTheFirstUntrustedAddressFromTheRight) {
  const TrustedProxies proxies = Trusting({"127.0.0.1", "10.0.0.0/8"});
  // Not from a proxy: whatever the header says, the client is the peer.
  EXPECT_EQ(Address(proxies, "203.0.113.5", "198.51.100.1"), "203.0.113.5");
  // From a proxy that forwarded for a client.
  EXPECT_EQ(Address(proxies, "127.0.0.1", "198.51.100.1"), "198.51.100.1+");
  // Through two proxies; what the client wrote itself (left of the first proxy's entry) is not
  // believed.
  EXPECT_EQ(Address(proxies, "127.0.0.1", "6.6.6.6, 198.51.100.1, 10.0.0.4"), "198.51.100.1+");
  // Several headers arrive joined by commas; empty entries say nothing.
  EXPECT_EQ(Address(proxies, "127.0.0.1", "198.51.100.1,,10.0.0.4, "), "198.51.100.1+");
  // Ports and brackets are written by some proxies; the client is the address alone.
  EXPECT_EQ(Address(proxies, "127.0.0.1", "[2001:db8::1]:443"), "2001:db8::1+");
  EXPECT_EQ(Address(proxies, "127.0.0.1", "198.51.100.1:5000"), "198.51.100.1+");
  // An entry that is no address stops at the trusted hop that passed it on.
  EXPECT_EQ(Address(proxies, "127.0.0.1", "<script>"), "127.0.0.1");
  EXPECT_EQ(Address(proxies, "127.0.0.1", "198.51.100.1, unknown, 10.0.0.4"), "10.0.0.4+");
  // No header, or nothing but proxies: the leftmost proxy is as far as anyone can see.
  EXPECT_EQ(Address(proxies, "127.0.0.1", ""), "127.0.0.1");
  EXPECT_EQ(Address(proxies, "127.0.0.1", "10.0.0.9, 10.0.0.4"), "10.0.0.9+");
  // A client on the proxy's own host: named by the header, though its address is the peer's.
  EXPECT_EQ(Address(proxies, "127.0.0.1", "127.0.0.1"), "127.0.0.1+");
  // Trusting no one, the header is never read.
  EXPECT_EQ(Address(TrustedProxies(), "127.0.0.1", "198.51.100.1"), "127.0.0.1");
}

}  // namespace
}  // namespace pintag::server
