// Sort plans: longest prefix wins, explicit fallback, unknown plan, CSV in and out.

#include <gtest/gtest.h>

#include <algorithm>
#include <functional>

#include "db_test_util.hpp"
#include "pintag/db/sort_plan.hpp"
#include "pintag/db/text.hpp"

namespace pintag::db {
namespace {

using test::TempDir;

SortPlan HubPlan() {
  return {"hub-a",
          "reject",
          "test plan",
          {{"1", "north"}, {"11", "delhi"}, {"110001", "parliament"}, {"56", "bengaluru"}}};
}

class SortPlans : public ::testing::Test {
 protected:
  TempDir dir_;
  Connection db_ = test::OpenExisting(test::CopyOfSeeded(dir_));
};

TEST_F(SortPlans, LongestPrefixWinsElseTheFallback) {
  ASSERT_TRUE(SavePlan(db_, HubPlan()).ok());
  const struct {
    std::uint32_t pincode;
    const char* bin;
    const char* prefix;  // nullptr: the fallback
  } cases[] = {{110001, "parliament", "110001"}, {110002, "delhi", "11"},
               {123456, "north", "1"},           {560001, "bengaluru", "56"},
               {600001, "reject", nullptr},      {999999, "reject", nullptr}};
  const SortPlan plan = GetPlan(db_, "hub-a").value();
  for (const auto& c : cases) {
    const auto routed = Route(db_, Pincode(c.pincode), "hub-a");
    ASSERT_TRUE(routed.ok()) << routed.error().message;
    EXPECT_EQ(routed->bin, c.bin) << c.pincode;
    if (c.prefix == nullptr) {
      EXPECT_FALSE(routed->rule.has_value()) << c.pincode;
    } else {
      ASSERT_TRUE(routed->rule.has_value()) << c.pincode;
      EXPECT_EQ(routed->rule->prefix, c.prefix);
      EXPECT_EQ(routed->rule->bin, c.bin);
    }
    const Routing in_memory = RouteWith(plan, Pincode(c.pincode));
    EXPECT_EQ(in_memory.bin, routed->bin);
    EXPECT_EQ(in_memory.rule, routed->rule);
  }
}

TEST_F(SortPlans, UnknownPlanIsAnErrorValue) {
  const auto routed = Route(db_, Pincode(110001), "no-such-plan");
  ASSERT_FALSE(routed.ok());
  EXPECT_EQ(routed.error().code, ErrorCode::kNotFound);
  EXPECT_NE(routed.error().message.find("no-such-plan"), std::string::npos);
  EXPECT_EQ(GetPlan(db_, "no-such-plan").error().code, ErrorCode::kNotFound);
  EXPECT_EQ(DeletePlan(db_, "no-such-plan").error().code, ErrorCode::kNotFound);
  EXPECT_FALSE(HasPlan(db_, "no-such-plan").value());
  EXPECT_TRUE(HasPlan(db_, "default").value());
}

TEST_F(SortPlans, SavingReplacesAndDeletingRemoves) {
  const Result<bool> created = SavePlan(db_, HubPlan());
  ASSERT_TRUE(created.ok());
  EXPECT_FALSE(created.value()) << "a new name is created, not replaced";
  SortPlan smaller{"hub-a", "other", "", {{"2", "two"}}};
  const Result<bool> replaced = SavePlan(db_, smaller);
  ASSERT_TRUE(replaced.ok());
  EXPECT_TRUE(replaced.value());
  const SortPlan stored = GetPlan(db_, "hub-a").value();
  EXPECT_EQ(stored.rules, smaller.rules);
  EXPECT_EQ(stored.fallback_bin, "other");
  EXPECT_EQ(ListPlans(db_).value(), (std::vector<std::string>{"default", "hub-a"}));
  EXPECT_TRUE(HasPlan(db_, "hub-a").value());
  ASSERT_TRUE(DeletePlan(db_, "hub-a").ok());
  EXPECT_FALSE(HasPlan(db_, "hub-a").value());
  EXPECT_EQ(db_.queryInt64("SELECT count(*) FROM sort_rules WHERE bin = 'two'"), 0);
}

TEST_F(SortPlans, DeletingAnswersThePlanAsItWasAndHonoursTheVersionRead) {
  const SortPlan hub = HubPlan();
  ASSERT_TRUE(SavePlan(db_, hub).ok());
  const std::string version = PlanVersion(GetPlan(db_, hub.name).value());

  const PlanCondition other{PlanVersions{false, {"0123"}}, std::nullopt};
  EXPECT_EQ(DeletePlan(db_, hub.name, other).error().code, ErrorCode::kPrecondition);
  EXPECT_TRUE(HasPlan(db_, hub.name).value());

  const PlanCondition read{PlanVersions{false, {version}}, std::nullopt};
  const Result<SortPlan> deleted = DeletePlan(db_, hub.name, read);
  ASSERT_TRUE(deleted.ok()) << deleted.error().message;
  EXPECT_EQ(PlanVersion(deleted.value()), version);
  EXPECT_EQ(deleted->rules.size(), hub.rules.size());
  EXPECT_FALSE(HasPlan(db_, hub.name).value());
  EXPECT_EQ(DeletePlan(db_, hub.name, read).error().code, ErrorCode::kPrecondition);
  EXPECT_EQ(DeletePlan(db_, hub.name).error().code, ErrorCode::kNotFound);
}

TEST_F(SortPlans, TheDefaultPlanIsNeverDeleted) {
  const std::size_t rules = GetPlan(db_, kDefaultPlanName).value().rules.size();
  ASSERT_GT(rules, 0U);
  const Result<SortPlan> refused = DeletePlan(db_, kDefaultPlanName);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, ErrorCode::kConflict);
  EXPECT_EQ(GetPlan(db_, kDefaultPlanName).value().rules.size(), rules);
}

TEST_F(SortPlans, KeepingTheStoredDescriptionKeepsItOnlyWhenThereIsOne) {
  ASSERT_TRUE(SavePlan(db_, HubPlan()).ok());  // "test plan"
  SortPlan from_csv{"hub-a", "other", "", {{"2", "two"}}};
  ASSERT_TRUE(SavePlan(db_, from_csv, StoredDescription::kKeep).ok());
  EXPECT_EQ(GetPlan(db_, "hub-a").value().description, "test plan");
  EXPECT_EQ(GetPlan(db_, "hub-a").value().rules, from_csv.rules);
  SortPlan fresh{"hub-b", "other", "given", {{"2", "two"}}};
  ASSERT_TRUE(SavePlan(db_, fresh, StoredDescription::kKeep).ok());
  EXPECT_EQ(GetPlan(db_, "hub-b").value().description, "given");
  ASSERT_TRUE(SavePlan(db_, from_csv).ok());  // kReplace: the description given, empty
  EXPECT_EQ(GetPlan(db_, "hub-a").value().description, "");
}

TEST_F(SortPlans, VersionNamesEverythingStored) {
  const SortPlan plan = HubPlan();
  EXPECT_EQ(PlanVersion(plan).size(), 32U);
  SortPlan reordered = plan;
  std::reverse(reordered.rules.begin(), reordered.rules.end());
  EXPECT_EQ(PlanVersion(reordered), PlanVersion(plan));  // rules are a set, kept by prefix
  const std::vector<std::function<void(SortPlan&)>> changes = {
      [](SortPlan& p) { p.description += "."; }, [](SortPlan& p) { p.fallback_bin += "."; },
      [](SortPlan& p) { p.rules[0].bin += "."; }, [](SortPlan& p) { p.rules.pop_back(); }};
  for (std::size_t i = 0; i < changes.size(); ++i) {
    SortPlan changed = plan;
    changes[i](changed);
    EXPECT_NE(PlanVersion(changed), PlanVersion(plan)) << "change " << i;
  }
  // Field boundaries count: "ab" + "c" is not "a" + "bc".
  EXPECT_NE(PlanVersion({"p", "ab", "c", {}}), PlanVersion({"p", "a", "bc", {}}));
}

TEST_F(SortPlans, ConditionalSaveChecksTheStoredVersionFirst) {
  const auto saved = SavePlanIf(db_, HubPlan(), {std::nullopt, PlanVersions{true, {}}});
  ASSERT_TRUE(saved.ok()) << saved.error().message;
  EXPECT_FALSE(saved->replaced);
  EXPECT_EQ(saved->version, PlanVersion(GetPlan(db_, "hub-a").value()));

  // If-None-Match: * on a stored plan, If-Match on a version it is not at, or on no plan at all.
  SortPlan other{"hub-a", "other", "", {{"2", "two"}}};
  const auto exists = SavePlanIf(db_, other, {std::nullopt, PlanVersions{true, {}}});
  ASSERT_FALSE(exists.ok());
  EXPECT_EQ(exists.error().code, ErrorCode::kPrecondition);
  const auto stale = SavePlanIf(db_, other, {PlanVersions{false, {"0123"}}, std::nullopt});
  ASSERT_FALSE(stale.ok());
  EXPECT_EQ(stale.error().code, ErrorCode::kPrecondition);
  EXPECT_NE(stale.error().message.find(saved->version), std::string::npos);
  SortPlan absent = other;
  absent.name = "hub-z";
  EXPECT_EQ(SavePlanIf(db_, absent, {PlanVersions{true, {}}, std::nullopt}).error().code,
            ErrorCode::kPrecondition);
  EXPECT_EQ(GetPlan(db_, "hub-a").value(), HubPlan());
  EXPECT_EQ(GetPlan(db_, "hub-z").error().code, ErrorCode::kNotFound);

  // The version read is met once; the writer after it holds a stale one.
  const PlanCondition read_at{PlanVersions{false, {"elsewhere", saved->version}}, std::nullopt};
  const auto first = SavePlanIf(db_, other, read_at);
  ASSERT_TRUE(first.ok()) << first.error().message;
  EXPECT_TRUE(first->replaced);
  EXPECT_EQ(first->plan, other);
  SortPlan second = HubPlan();
  second.fallback_bin = "lost";
  EXPECT_EQ(SavePlanIf(db_, second, read_at).error().code, ErrorCode::kPrecondition);
  EXPECT_EQ(GetPlan(db_, "hub-a").value(), other);
}

TEST_F(SortPlans, RejectsMalformedPlans) {
  SortPlan plan = HubPlan();
  plan.rules.push_back({"1234567", "x"});
  EXPECT_EQ(SavePlan(db_, plan).error().code, ErrorCode::kInvalid);
  plan = HubPlan();
  plan.rules.push_back({"1a", "x"});
  EXPECT_EQ(SavePlan(db_, plan).error().code, ErrorCode::kInvalid);
  plan = HubPlan();
  plan.rules.push_back({"11", "again"});
  EXPECT_EQ(SavePlan(db_, plan).error().code, ErrorCode::kInvalid);
  plan = HubPlan();
  plan.fallback_bin.clear();
  EXPECT_EQ(SavePlan(db_, plan).error().code, ErrorCode::kInvalid);
  plan = HubPlan();
  plan.rules.push_back({"", "x"});
  EXPECT_EQ(SavePlan(db_, plan).error().code, ErrorCode::kInvalid);
  EXPECT_EQ(GetPlan(db_, "hub-a").error().code, ErrorCode::kNotFound);
}

// Plans listed as four "default"s (" default", "default ", "default" and one ending in a
// zero-width space), a bin " delhi" beside "delhi", and a plan called ".." that a URL cannot
// name: refused, each saying why. Names and bins that read as they are still save.
TEST_F(SortPlans, NamesAndBinsMustReadAsWhatTheyAre) {
  const auto refusal = [&](const std::string& name, const std::string& bin) {
    SortPlan plan = HubPlan();
    plan.name = name;
    plan.rules.push_back({"560", bin});
    const auto saved = SavePlan(db_, plan);
    return saved ? std::string() : saved.error().message;
  };
  for (const std::string& name :
       {std::string(" default"), std::string("default "), std::string("default\u200b"),
        std::string("de\u00a0fault"), std::string("\ufeffdefault")}) {
    EXPECT_NE(refusal(name, "south").find("it would read like another name"), std::string::npos)
        << name;
  }
  for (const std::string& name :
       {std::string("."), std::string(".."), std::string("a/b"), std::string("hub?x=1"),
        std::string("h#x"), std::string("p%"), std::string("a\\b"), std::string("a+b"),
        std::string("a&b"), std::string("a=b")}) {
    EXPECT_NE(refusal(name, "south").find("which a URL would have to encode"), std::string::npos)
        << name;
  }
  for (const std::string& bin : {std::string(" delhi"), std::string("delhi\t"),
                                 std::string("del\u200bhi"), std::string("\u2060delhi")}) {
    EXPECT_FALSE(refusal("hub-b", bin).empty()) << bin;
  }
  EXPECT_EQ(GetPlan(db_, "hub-b").error().code, ErrorCode::kNotFound);
  // Inner spaces, dots and the joiners of Indic words are names as they read.
  EXPECT_EQ(refusal("hub b.2", "south zone"), "");
  EXPECT_EQ(refusal("hub-c", "\u0926\u093f\u200d\u0932\u094d\u0932\u0940"), "");
  // Kannur in Malayalam's older chillu form ends in a zero-width joiner.
  EXPECT_EQ(refusal("hub-d", "\u0d15\u0d23\u0d4d\u0d23\u0d42\u0d30\u0d4d\u200d"), "");
  EXPECT_FALSE(refusal("hub-e", "\u200dkannur").empty());
  // The plan's CSV is opened in spreadsheets, which run a cell starting with = + - @.
  for (const std::string& bin : {std::string("=HYPERLINK(\"x\")"), std::string("+91"),
                                 std::string("-2"), std::string("@sum")}) {
    EXPECT_NE(refusal("hub-f", bin).find("runs as a formula"), std::string::npos) << bin;
  }
  EXPECT_EQ(refusal("hub-f", "a=b+c-d@e"), "");
  // A spreadsheet whose list separator is ';' split a bare "a;=1+1" into a cell "=1+1", which it
  // ran: a bin holding one is quoted in the CSV, so it stays one cell, and reads back whole.
  SortPlan semicolons = HubPlan();
  semicolons.name = "hub-g";
  semicolons.rules.front().bin = "a;=1+1";
  const std::string csv = PlanToCsv(semicolons);
  EXPECT_NE(csv.find("," + std::string("\"a;=1+1\"") + "\n"), std::string::npos) << csv;
  const auto read_back = ParsePlanCsv("hub-g", csv);
  ASSERT_TRUE(read_back.ok()) << read_back.error().message;
  EXPECT_EQ(PlanToCsv(*read_back), csv);
  ASSERT_EQ(read_back->rules.size(), semicolons.rules.size());
  EXPECT_EQ(read_back->rules.front().bin, "a;=1+1");
  SortPlan formula_fallback = HubPlan();
  formula_fallback.fallback_bin = "=1+1";
  EXPECT_FALSE(SavePlan(db_, formula_fallback).ok());
  const auto from_csv = ParsePlanCsv("x", "prefix,bin\n*,ok\n11,\"=cmd|' /c calc'!A0\"\n");
  ASSERT_FALSE(from_csv.ok());
  EXPECT_EQ(from_csv.error().message.rfind("line 3: bin for prefix 11 '=cmd", 0), 0U)
      << from_csv.error().message;
  EXPECT_FALSE(ParsePlanCsv("x", "prefix,bin\n*,@floor\n").ok());
}

// "Café" with é as one character (U+00E9) or as e and U+0301, and a Devanagari consonant with
// its nukta or in its precomposed form, read alike. Two bins or two plans so written would show as
// one and be two, so the second is refused, naming the first; text is kept as written.
TEST_F(SortPlans, NamesAndBinsThatReadAlikeButDifferInCodePointsAreNotTwo) {
  const std::string composed = "caf\u00e9";     // é
  const std::string decomposed = "cafe\u0301";  // e + combining acute
  const std::string qa_precomposed = "\u0958";  // क़ (a composition exclusion)
  const std::string qa_with_nukta = "\u0915\u093c";
  ASSERT_NE(composed, decomposed);
  EXPECT_EQ(CanonicalForm(decomposed), composed);
  EXPECT_EQ(CanonicalForm(qa_precomposed), qa_with_nukta);
  EXPECT_NE(CanonicalForm("cafe"), CanonicalForm(composed));
  EXPECT_EQ(CanonicalForm("\xff\xfe"), "\xff\xfe");  // not UTF-8: unchanged
  // GLib's normaliser stops at a NUL: such text is not cut to read like another.
  const std::string with_nul = decomposed + std::string(1, '\0') + "zz";
  EXPECT_EQ(CanonicalForm(with_nul), with_nul);

  SortPlan bins = HubPlan();
  bins.rules.push_back({"60", composed});
  bins.rules.push_back({"61", decomposed});
  const auto mixed = SavePlan(db_, bins);
  ASSERT_FALSE(mixed.ok());
  EXPECT_EQ(mixed.error().code, ErrorCode::kInvalid);
  // Both named, each with its code points beyond ASCII, since they print alike.
  EXPECT_NE(mixed.error().message.find("bin for prefix 61 '" + decomposed +
                                       "' (U+0301) and the bin for prefix 60 '" + composed +
                                       "' (U+00E9) read the same"),
            std::string::npos)
      << mixed.error().message;
  const auto from_csv =
      ParsePlanCsv("x", "prefix,bin\n*," + qa_precomposed + "\n11," + qa_with_nukta + "\n");
  ASSERT_FALSE(from_csv.ok());
  EXPECT_NE(from_csv.error().message.find("fallback bin"), std::string::npos);
  // One bin written the same way on every rule, in either form, is a plan.
  bins.rules.back().bin = composed;
  ASSERT_TRUE(SavePlan(db_, bins).ok());
  SortPlan decomposed_bins = HubPlan();
  decomposed_bins.name = "hub-nfd";
  decomposed_bins.rules = {{"60", decomposed}, {"61", decomposed}};
  ASSERT_TRUE(SavePlan(db_, decomposed_bins).ok());
  EXPECT_EQ(GetPlan(db_, "hub-nfd")->rules[0].bin, decomposed);  // stored as written

  SortPlan first = HubPlan();
  first.name = "hub-" + composed;
  ASSERT_TRUE(SavePlan(db_, first).ok());
  SortPlan second = HubPlan();
  second.name = "hub-" + decomposed;
  const auto twin = SavePlan(db_, second);
  ASSERT_FALSE(twin.ok());
  EXPECT_EQ(twin.error().code, ErrorCode::kConflict);
  EXPECT_NE(twin.error().message.find("the plan '" + first.name + "' (U+00E9) reads the same as '" +
                                      second.name + "' (U+0301)"),
            std::string::npos)
      << twin.error().message;
  EXPECT_FALSE(HasPlan(db_, second.name).value());
  // The plan is changed under its stored name; asked for by the other, the answer names it.
  EXPECT_TRUE(SavePlan(db_, first).value());
  const auto asked = GetPlan(db_, second.name);
  ASSERT_FALSE(asked.ok());
  EXPECT_EQ(asked.error().code, ErrorCode::kNotFound);
  EXPECT_NE(asked.error().message.find("'" + first.name + "' (U+00E9) reads the same"),
            std::string::npos)
      << asked.error().message;
  const auto routed = Route(db_, Pincode(110001), second.name);
  ASSERT_FALSE(routed.ok());
  EXPECT_NE(routed.error().message.find(first.name), std::string::npos);
  // A conditional replace or delete by the other name: 412, saying the same.
  PlanCondition any;
  any.match = PlanVersions{.any = true, .versions = {}};
  const auto replaced = SavePlanIf(db_, second, any);
  ASSERT_FALSE(replaced.ok());
  EXPECT_EQ(replaced.error().code, ErrorCode::kPrecondition);
  EXPECT_NE(replaced.error().message.find("'" + first.name + "' (U+00E9) reads the same"),
            std::string::npos)
      << replaced.error().message;
  const auto deleted = DeletePlan(db_, second.name, any);
  ASSERT_FALSE(deleted.ok());
  EXPECT_EQ(deleted.error().code, ErrorCode::kPrecondition);
  EXPECT_NE(deleted.error().message.find("'" + first.name + "' (U+00E9) reads the same"),
            std::string::npos)
      << deleted.error().message;
  EXPECT_TRUE(HasPlan(db_, first.name).value());
}

TEST_F(SortPlans, CsvRoundTripsAndReportsLines) {
  const SortPlan plan = HubPlan();
  const std::string csv = PlanToCsv(plan);
  EXPECT_EQ(csv, "prefix,bin\n*,reject\n1,north\n11,delhi\n110001,parliament\n56,bengaluru\n");
  const auto parsed = ParsePlanCsv("hub-a", csv);
  ASSERT_TRUE(parsed.ok()) << parsed.error().message;
  EXPECT_EQ(parsed->rules, plan.rules);
  EXPECT_EQ(parsed->fallback_bin, "reject");

  const auto quoted =
      ParsePlanCsv("q", "prefix,bin\r\n*,\"bin, with comma\"\r\n2,\"say \"\"hi\"\"\"\r\n");
  ASSERT_TRUE(quoted.ok()) << quoted.error().message;
  EXPECT_EQ(quoted->fallback_bin, "bin, with comma");
  EXPECT_EQ(quoted->rules[0].bin, "say \"hi\"");
  EXPECT_EQ(ParsePlanCsv("q", PlanToCsv(*quoted)).value().rules, quoted->rules);
  // Written by hand with spaces after the commas: read as the fields they surround.
  const auto spaced = ParsePlanCsv("s", "prefix, bin\n*, floor\n11, delhi \n 56 ,south zone\n");
  ASSERT_TRUE(spaced.ok()) << spaced.error().message;
  EXPECT_EQ(spaced->fallback_bin, "floor");
  EXPECT_EQ(spaced->rules, (std::vector<SortRule>{{"11", "delhi"}, {"56", "south zone"}}));
  // Spaces around a quoted field too (both were "stray double quote" / "text after a closing
  // quote"); a space inside the quotes is the bin's, and refused as one at its end.
  const auto spaced_quotes =
      ParsePlanCsv("s", "prefix,bin\n*, \"floor, east\"\n\"11\" ,delhi\n56,  \"a \"\"b\"\"\"  \n");
  ASSERT_TRUE(spaced_quotes.ok()) << spaced_quotes.error().message;
  EXPECT_EQ(spaced_quotes->fallback_bin, "floor, east");
  EXPECT_EQ(spaced_quotes->rules, (std::vector<SortRule>{{"11", "delhi"}, {"56", "a \"b\""}}));
  const auto after_quote = ParsePlanCsv("x", "prefix,bin\n*,\"a\"b\n");
  ASSERT_FALSE(after_quote.ok());
  EXPECT_NE(after_quote.error().message.find("text after a closing quote"), std::string::npos);
  // A line of a million commas is refused by its field count without keeping a field for each.
  const auto commas = ParsePlanCsv("x", "prefix,bin\n*,a\n" + std::string(1'000'000, ','));
  ASSERT_FALSE(commas.ok());
  EXPECT_NE(commas.error().message.find("more than 256 fields"), std::string::npos)
      << commas.error().message;
  // The limit is exact: 256 fields are counted, 257 refused.
  EXPECT_EQ(ParsePlanCsv("x", "prefix,bin\n*,a\n" + std::string(255, ',')).error().message,
            "line 3: expected 2 fields, got 256");
  EXPECT_EQ(ParsePlanCsv("x", "prefix,bin\n*,a\n" + std::string(256, ',')).error().message,
            "line 3: more than 256 fields");

  const auto no_fallback = ParsePlanCsv("x", "prefix,bin\n1,a\n");
  ASSERT_FALSE(no_fallback.ok());
  EXPECT_NE(no_fallback.error().message.find("fallback"), std::string::npos);
  const auto two = ParsePlanCsv("x", "prefix,bin\n*,a\n1,b\n*,c\n");
  ASSERT_FALSE(two.ok());
  EXPECT_NE(two.error().message.find("line 4"), std::string::npos) << two.error().message;
  const auto wide = ParsePlanCsv("x", "prefix,bin\n*,a\n1,b,c\n");
  ASSERT_FALSE(wide.ok());
  EXPECT_NE(wide.error().message.find("line 3"), std::string::npos);
  EXPECT_FALSE(ParsePlanCsv("x", "pin,bin\n*,a\n").ok());
  EXPECT_FALSE(ParsePlanCsv("x", "prefix,bin\n*,a\n12345a,b\n").ok());
  // A rule no pincode can match (none starts with 0), and a prefix twice: both lines named.
  const auto zero = ParsePlanCsv("x", "prefix,bin\n*,a\n1,b\n012345,z\n");
  ASSERT_FALSE(zero.ok());
  EXPECT_EQ(zero.error().message.rfind("line 4: rule prefix '012345' starts with 0", 0), 0U)
      << zero.error().message;
  const auto twice = ParsePlanCsv("x", "prefix,bin\n*,a\n11,b\n56,c\n11,d\n");
  ASSERT_FALSE(twice.ok());
  EXPECT_EQ(twice.error().message, "line 5: prefix 11 appears twice (first on line 3)");
}

TEST_F(SortPlans, RulesPerPlanAreLimited) {
  SortPlan plan{"big", "m", "", {}};
  std::string csv = "prefix,bin\n*,m\n";
  for (std::size_t i = 0; i < kMaxPlanRules; ++i) {
    plan.rules.push_back({std::to_string(100000 + i), "b"});
    csv += plan.rules.back().prefix + ",b\n";
  }
  EXPECT_FALSE(CheckPlan(plan).has_value());
  ASSERT_TRUE(ParsePlanCsv("big", csv).ok());
  plan.rules.push_back({"1", "one too many"});
  ASSERT_TRUE(CheckPlan(plan).has_value());
  EXPECT_EQ(CheckPlan(plan)->code, ErrorCode::kTooLarge);
  EXPECT_EQ(SavePlan(db_, plan).error().code, ErrorCode::kTooLarge);
  const auto over = ParsePlanCsv("big", csv + "1,one too many\n");
  ASSERT_FALSE(over.ok());
  EXPECT_EQ(over.error().code, ErrorCode::kTooLarge);
  EXPECT_EQ(over.error().message, "line 100003: a sort plan has at most 100000 rules");
  EXPECT_EQ(GetPlan(db_, "big").error().code, ErrorCode::kNotFound);
}

}  // namespace
}  // namespace pintag::db
