// JsonWriter against an independent parser (nlohmann::json): whatever it writes parses, and reads
// back as the values written, including hostile text and doubles at the edges of precision.

#include "pintag/server/json_writer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>

namespace pintag::server {
namespace {

TEST(JsonWriter, NestedValuesReadBackAsWritten) {
  JsonWriter out;
  out.beginObject();
  out.key("a").value(std::int64_t{-9'223'372'036'854'775'807 - 1});
  out.key("b").beginArray().value(true).value(false).null().value(std::optional<int>{}).endArray();
  out.key("c").beginObject().endObject();
  out.key("d").beginArray().beginArray().endArray().beginObject().key("e").value(1).endObject();
  out.endArray();
  out.key("f").value(std::optional<std::string>("text"));
  out.endObject();
  const nlohmann::json parsed = nlohmann::json::parse(out.take());
  EXPECT_EQ(parsed["a"].get<std::int64_t>(), std::numeric_limits<std::int64_t>::min());
  EXPECT_EQ(parsed["b"], nlohmann::json::parse("[true, false, null, null]"));
  EXPECT_TRUE(parsed["c"].is_object() && parsed["c"].empty());
  EXPECT_EQ(parsed["d"], nlohmann::json::parse(R"([[], {"e": 1}])"));
  EXPECT_EQ(parsed["f"], "text");
  EXPECT_EQ(parsed.size(), 5u);
}

TEST(JsonWriter, EveryAsciiAndControlCharacterRoundTrips) {
  std::string all;
  for (int c = 0; c < 0x80; ++c) all += static_cast<char>(c);
  all += "ü — नमस्ते 😀";  // two-, three- and four-byte UTF-8
  JsonWriter out;
  out.beginArray().value(all).endArray();
  const std::string text = out.take();
  EXPECT_EQ(nlohmann::json::parse(text)[0].get<std::string>(), all);
  // Raw control characters are never written (RFC 8259 forbids them inside strings).
  for (char c : text) EXPECT_GE(static_cast<unsigned char>(c), 0x20);
}

TEST(JsonWriter, BytesThatAreNotUtf8BecomeReplacementCharacters) {
  // "a\xC0\xAF" "b" is one string, split so that the hex escape does not take in the b.
  const std::string bad[] = {"\xFF",
                             "a\xC0\xAF"  // NOLINT(bugprone-suspicious-missing-comma)
                             "b",
                             "\xED\xA0\x80",
                             "\xF4\x90\x80\x80",
                             "\xE2\x82",
                             "\x80"};
  for (const std::string& text : bad) {
    JsonWriter out;
    out.value(text);
    const std::string written = out.take();
    // nlohmann refuses invalid UTF-8, so parsing at all proves the output is valid.
    const auto parsed = nlohmann::json::parse(written).get<std::string>();
    EXPECT_NE(parsed.find("\xEF\xBF\xBD"), std::string::npos) << written;
  }
}

TEST(JsonWriter, DoublesReadBackExactlyAndNonFiniteAreNull) {
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> uniform(-1e6, 1e6);
  std::vector<double> values = {0.0,
                                -0.0,
                                1.0 / 3.0,
                                28.6139,
                                77.209,
                                1e-300,
                                1.7976931348623157e308,
                                std::numeric_limits<double>::denorm_min()};
  for (int i = 0; i < 1000; ++i) values.push_back(uniform(random));
  JsonWriter out;
  out.beginArray();
  for (double v : values) out.value(v);
  out.value(std::nan("")).value(std::numeric_limits<double>::infinity());
  out.endArray();
  const nlohmann::json parsed = nlohmann::json::parse(out.take());
  ASSERT_EQ(parsed.size(), values.size() + 2);
  for (std::size_t i = 0; i < values.size(); ++i) EXPECT_EQ(parsed[i].get<double>(), values[i]);
  EXPECT_TRUE(parsed[values.size()].is_null());
  EXPECT_TRUE(parsed[values.size() + 1].is_null());
}

TEST(JsonWriter, WholeDoublesStayFloatsAndIntegersOfEveryWidthAreNumbers) {
  JsonWriter out;
  out.beginArray().value(28.0).value(-0.0).value(1e21).value(std::uint8_t{200});
  out.value(std::uint32_t{4'000'000'000}).value(short{-5}).value(std::size_t{21}).endArray();
  const std::string text = out.take();
  const nlohmann::json parsed = nlohmann::json::parse(text);
  EXPECT_TRUE(parsed[0].is_number_float()) << text;
  EXPECT_EQ(parsed[0].get<double>(), 28.0);
  EXPECT_TRUE(parsed[1].is_number_float() && std::signbit(parsed[1].get<double>())) << text;
  EXPECT_TRUE(parsed[2].is_number_float()) << text;
  EXPECT_EQ(parsed[3], 200);
  EXPECT_EQ(parsed[4].get<std::int64_t>(), 4'000'000'000);
  EXPECT_EQ(parsed[5], -5);
  EXPECT_TRUE(parsed[6].is_number_integer());
}

TEST(JsonWriter, KeysAreEscapedAndTakeLeavesTheWriterEmpty) {
  JsonWriter out;
  out.beginObject().key("quote\"back\\slash\n").value(1).endObject();
  EXPECT_EQ(nlohmann::json::parse(out.take())["quote\"back\\slash\n"], 1);
  out.beginArray().value(2).endArray();
  EXPECT_EQ(out.take(), "[2]");
}

}  // namespace
}  // namespace pintag::server
