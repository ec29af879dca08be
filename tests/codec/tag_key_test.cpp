#include "pintag/codec/tag_key.hpp"

#include <gtest/gtest.h>

#include <string>

namespace pintag {
namespace {

TEST(TagKey, ParsesEveryKeyFromZeroTo32767) {
  for (const auto& [text, value] :
       {std::pair{"0", 0}, std::pair{"7", 7}, std::pair{"11684", 11684}, std::pair{"32767", 32767},
        std::pair{"00042", 42}, std::pair{"000001", 1}, std::pair{"0000000000032767", 32767},
        std::pair{"000", 0}}) {
    const ParsedTagKey parsed = ParseTagKey(text);
    ASSERT_TRUE(parsed) << text << ": " << parsed.error;
    EXPECT_EQ(parsed.key->value(), value) << text;
  }
}

TEST(TagKey, RejectsEverythingElseWithAReason) {
  for (const std::string& text :
       {std::string(""), std::string("32768"), std::string("65535"), std::string("-1"),
        std::string("+1"), std::string(" 1"), std::string("1 "), std::string("1e3"),
        std::string("0x10"), std::string("1.0"), std::string("99999999999999999999"),
        std::string("0032768"), std::string("00-1"), std::string("000 "), std::string("1\0", 2),
        std::string("١٢")}) {
    const ParsedTagKey parsed = ParseTagKey(text);
    EXPECT_FALSE(parsed) << testing::PrintToString(text);
    EXPECT_NE(parsed.error.find("0 to 32767"), std::string::npos) << parsed.error;
  }
}

}  // namespace
}  // namespace pintag
