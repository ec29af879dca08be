// The chunked body's framing check, fed as the server's reads feed it: in any split of the bytes
// (cpp-httplib reads lines a byte at a time and data in blocks), the same verdict.

#include "http/chunked_body_check.hpp"

#include <gtest/gtest.h>

#include <optional>
#include <string>
#include <vector>

namespace pintag::server {
namespace {

/// The check's refusal after `body`, taken whole, a byte at a time, and in blocks of 3: the same
/// in every split, else the test fails. Nothing when the body is whole and well framed.
std::optional<std::string> Verdict(const std::string& body, bool* ended = nullptr) {
  std::vector<std::optional<std::string>> verdicts;
  std::vector<bool> ends;
  for (const std::size_t block : {body.size() + 1, std::size_t{1}, std::size_t{3}}) {
    ChunkedBodyCheck check;
    for (std::size_t at = 0; at < body.size() && check.take(body.substr(at, block)); at += block) {
    }
    verdicts.push_back(check.refusal());
    ends.push_back(check.ended());
  }
  EXPECT_EQ(verdicts[1], verdicts[0]) << body;
  EXPECT_EQ(verdicts[2], verdicts[0]) << body;
  EXPECT_EQ(ends[1], ends[0]) << body;
  EXPECT_EQ(ends[2], ends[0]) << body;
  if (ended != nullptr) *ended = ends[0];
  return verdicts[0];
}

TEST(ChunkedBodyCheck, WellFramedBodiesPassAndEnd) {
  for (const std::string body :
       {"5\r\nhello\r\n0\r\n\r\n", "A\r\n0123456789\r\n0\r\n\r\n",
        "000a\r\n0123456789\r\n0\r\n\r\n", "3;name=\"v\"\r\nabc\r\n2 ; x\r\nde\r\n0;last\r\n\r\n",
        "0\r\n\r\n", "1\r\n\r\r\n1\r\n\n\r\n0\r\n\r\n" /* data holding CR and LF */}) {
    bool ended = false;
    EXPECT_EQ(Verdict(body, &ended), std::nullopt) << body;
    EXPECT_TRUE(ended) << body;
  }
  // Cut anywhere before its last byte, a body is not refused, only not ended.
  const std::string whole = "5\r\nhello\r\n0\r\n\r\n";
  for (std::size_t cut = 0; cut < whole.size(); ++cut) {
    bool ended = true;
    EXPECT_EQ(Verdict(whole.substr(0, cut), &ended), std::nullopt) << cut;
    EXPECT_FALSE(ended) << cut;
  }
}

TEST(ChunkedBodyCheck, WhatARelaxedReaderWouldTakeIsRefusedSayingWhy) {
  const auto refused = [](const std::string& body, const std::string& says) {
    const std::optional<std::string> why = Verdict(body);
    ASSERT_TRUE(why.has_value()) << body;
    EXPECT_NE(why->find(says), std::string::npos) << body << ": " << *why;
  };
  refused("0x5\r\nhello\r\n0\r\n\r\n", "hexadecimal digits only");
  refused("+5\r\nhello\r\n0\r\n\r\n", "must start with a hexadecimal digit");
  refused("-5\r\nhello\r\n0\r\n\r\n", "must start with a hexadecimal digit");
  refused("5zz\r\nhello\r\n0\r\n\r\n", "hexadecimal digits only");
  refused("\r\nhello\r\n0\r\n\r\n", "must start with a hexadecimal digit");
  refused("5\nhello\r\n0\r\n\r\n", "not a bare LF");
  refused("5;x\nhello\r\n0\r\n\r\n", "not a bare LF");
  refused("5\rhello\r\n0\r\n\r\n", "must end in CRLF");
  refused("5\r\nhelloEXTRA\r\n0\r\n\r\n", "longer than its size says");
  refused("5\r\nhello\n0\r\n\r\n", "longer than its size says");
  refused("5\r\nhello\rX0\r\n\r\n", "followed by CRLF");
  refused("5\r\nhello\r\n0\r\nX-Trailer: 1\r\n\r\n", "trailer fields");
  refused("5\r\nhello\r\n0\r\n\rX", "must end in CRLF");
  refused("5\r\nhello\r\n0\r\n\r\nGET", "after its end");
  refused(std::string(17, '1') + "\r\n", "at most 16");
  refused("5;a\x01z\r\nhello\r\n0\r\n\r\n", "control character");
  // Sixteen digits is the most, and is not refused for its size here (the body limit is the
  // server's to hold); leading zeros are not counted (RFC 9112 allows them).
  EXPECT_EQ(Verdict(std::string(16, 'f') + "\r\nabc"), std::nullopt);
  EXPECT_EQ(Verdict(std::string(40, '0') + "5\r\nhello\r\n" + std::string(20, '0') + "\r\n\r\n"),
            std::nullopt);
  refused(std::string(20, '0') + std::string(17, '1') + "\r\n", "at most 16");
}

}  // namespace
}  // namespace pintag::server
