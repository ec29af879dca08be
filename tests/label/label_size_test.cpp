#include "pintag/codec/label_size.hpp"

#include <gtest/gtest.h>

namespace pintag {
namespace {

void ExpectSize(std::string_view text, double width_mm, double height_mm) {
  const ParsedLabelSize parsed = ParseLabelSize(text);
  ASSERT_TRUE(parsed) << text << ": " << parsed.error;
  EXPECT_NEAR(parsed.size->width_mm, width_mm, 1e-9) << text;
  EXPECT_NEAR(parsed.size->height_mm, height_mm, 1e-9) << text;
  EXPECT_TRUE(parsed.error.empty());
}

void ExpectError(std::string_view text, std::string_view fragment) {
  const ParsedLabelSize parsed = ParseLabelSize(text);
  EXPECT_FALSE(parsed) << text;
  EXPECT_NE(parsed.error.find(fragment), std::string::npos)
      << text << " gave '" << parsed.error << "', expected it to mention '" << fragment << "'";
}

TEST(LabelSize, ParsesTheCounterSizes) {
  ExpectSize("100x150mm", 100, 150);
  ExpectSize("a6", 105, 148);
  ExpectSize("A6", 105, 148);
  ExpectSize("4x6in", 101.6, 152.4);
  ExpectSize("4X6IN", 101.6, 152.4);
  ExpectSize(" 100 x 150 mm ", 100, 150);
  ExpectSize("10.5x14.8cm", 105, 148);
  ExpectSize("150x100mm", 150, 100);
  ExpectSize("75x75mm", 75, 75);
  ExpectSize("50x75mm", 50, 75);
  ExpectSize("150x300mm", 150, 300);
}

TEST(LabelSize, RefusesSizesWhoseTagWouldBeTooSmall) {
  // A near-square label stacks its three text rows above and below the tag: at 50 x 50 mm they
  // left it 3 mm of height.
  ExpectError("50x50mm", "at least 20 mm");
  ExpectError("60x60mm", "at least 20 mm");
  ExpectError("50x65mm", "at least 20 mm");
  for (const std::string_view fits : {"75x75mm", "50x75mm", "75x50mm", "2x3in", "50x100mm"}) {
    const ParsedLabelSize parsed = ParseLabelSize(fits);
    EXPECT_TRUE(parsed) << fits << ": " << parsed.error;
  }
}

TEST(LabelSize, NamedConstantsMatchTheirText) {
  EXPECT_EQ(*ParseLabelSize("a6").size, kLabelA6);
  EXPECT_EQ(*ParseLabelSize("4x6in").size, kLabel4x6In);
  EXPECT_EQ(*ParseLabelSize("100x150mm").size, kLabel100x150);
}

TEST(LabelSize, RoundTripsThroughText) {
  for (const LabelSize& size : {kLabel100x150, kLabelA6, kLabel4x6In, LabelSize{123.25, 80}}) {
    const ParsedLabelSize parsed = ParseLabelSize(ToString(size));
    ASSERT_TRUE(parsed) << ToString(size) << ": " << parsed.error;
    EXPECT_EQ(*parsed.size, size) << ToString(size);
  }
}

TEST(LabelSize, RefusesMalformedText) {
  ExpectError("", "empty");
  ExpectError("   ", "empty");
  ExpectError("100x150", "needs a unit");
  ExpectError("a4", "needs a unit");
  ExpectError("100x150px", "needs a unit");
  ExpectError("100mm", "WIDTHxHEIGHT");
  ExpectError("100x150x2mm", "WIDTHxHEIGHT");
  ExpectError("-100x150mm", "plain positive number");
  ExpectError("+100x150mm", "plain positive number");
  ExpectError("1e2x150mm", "plain positive number");
  ExpectError("infxnanmm", "plain positive number");
  ExpectError("1..0x150mm", "plain positive number");
  ExpectError(".x150mm", "plain positive number");
  ExpectError("x150mm", "plain positive number");
  // A side's number is at most 12 characters: said as such, not as "not a plain number".
  ExpectError("49.9999999999x100mm", "a side of more than 12 characters");
  ExpectError("100x150.00000000001mm", "a side of more than 12 characters");
  ExpectError("100x150mmmmmmmmmmmmmmmmmmmmmmmmmmmmmm", "too long");
}

TEST(LabelSize, EnforcesLimits) {
  ExpectError("49x100mm", "50 to 300 mm");
  ExpectError("100x301mm", "50 to 300 mm");
  ExpectError("0x0mm", "50 to 300 mm");
  ExpectError("12x12in", "50 to 300 mm");
  ExpectError("50x101mm", "aspect ratio");
  ExpectError("250x100mm", "aspect ratio");
  EXPECT_EQ(ValidateLabelSize(kLabel100x150), "");
  EXPECT_NE(ValidateLabelSize({std::numeric_limits<double>::quiet_NaN(), 100}), "");
}

}  // namespace
}  // namespace pintag
