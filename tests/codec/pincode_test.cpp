#include "pintag/codec/pincode.hpp"

#include <gtest/gtest.h>

#include <string>

namespace pintag {
namespace {

TEST(Pincode, AcceptsSixDigitsNotStartingWithZero) {
  for (const char* text : {"110001", "100000", "999999", "560034"}) {
    const ParsedPincode parsed = ParsePincode(text);
    ASSERT_TRUE(parsed) << text << ": " << parsed.error;
    EXPECT_EQ(parsed.pincode->str(), text);
    EXPECT_TRUE(parsed.error.empty());
  }
}

TEST(Pincode, RejectsEverythingElseWithAReason) {
  const std::string with_nul("11000\0", 6);
  for (const std::string& text :
       {std::string(""), std::string("11000"), std::string("1100011"), std::string("011000"),
        std::string(" 110001"), std::string("110001 "), std::string("+11000"),
        std::string("11 001"), std::string("11O001"), std::string("١١٠٠٠١"),
        std::string("１１０００１"), with_nul, std::string("-10001"), std::string("1e5000")}) {
    const ParsedPincode parsed = ParsePincode(text);
    EXPECT_FALSE(parsed) << text;
    EXPECT_FALSE(parsed.error.empty()) << text;
  }
  EXPECT_NE(ParsePincode("011000").error.find("start with 0"), std::string::npos);
  EXPECT_NE(ParsePincode("12345").error.find("6 digits"), std::string::npos);
  // Counted in characters, not bytes: six fullwidth or Arabic-Indic digits are six characters,
  // refused for their script, and seven of them are seven.
  for (const std::string text : {"１１０００１", "١١٠٠٠١", "११०००१", "110০01"}) {
    EXPECT_NE(ParsePincode(text).error.find("other scripts' digits"), std::string::npos) << text;
  }
  // A six-character text with another non-ASCII character is not told it holds such digits.
  for (const std::string text : {"11000é", "11000\u00a0", "Ω11000"}) {
    const std::string error = ParsePincode(text).error;
    EXPECT_NE(error.find("only the digits 0-9"), std::string::npos) << text;
    EXPECT_EQ(error.find("other scripts"), std::string::npos) << text;
  }
  EXPECT_NE(ParsePincode("１１０００１１").error.find("got 7 characters"), std::string::npos);
  EXPECT_NE(ParsePincode("11000\xff\xfe").error.find("got 7 characters"), std::string::npos);
}

}  // namespace
}  // namespace pintag
