// Hostile text in every text parameter: stored and returned verbatim, or rejected (kInvalid) —
// never executed.

#include <gtest/gtest.h>

#include <algorithm>

#include "db_test_util.hpp"
#include "pintag/db/csv.hpp"
#include "pintag/db/importer.hpp"
#include "pintag/db/registry.hpp"
#include "pintag/db/scan_log.hpp"
#include "pintag/db/sort_plan.hpp"
#include "pintag/db/text.hpp"
#include "pintag/db/tokens.hpp"

namespace pintag::db {
namespace {

using test::TempDir;

// Kept verbatim.
const std::vector<std::string> kAccepted = {
    "O'Brien",
    "\"double\" and 'single' quotes",
    "'; DROP TABLE pincodes; --",
    "Robert'); DROP TABLE offices;--",
    "x' OR '1'='1",
    "50%_off \\ back\\slash",
    "चाँदनी चौक",
    "Ελληνικά · 中文 · 😀",
    "  padded  ",
};

// Rejected: a NUL byte, very long text, invalid UTF-8, control characters (C0, and C1's CSI, which
// a terminal takes as an escape), a line separator, and a bidi override ("Evilpolice" on screen).
const std::vector<std::string> kRejected = {
    std::string("nul\0byte", 8),
    std::string(10000, 'a'),
    "\xff\xfe bad utf-8",
    "\xc0\xaf overlong",
    "line\nbreak",
    "tab\there",
    "Ab\u009b2Jcd",
    "Line\u2028Sep",
    "Evil\u202eecilop",
    "Iso\u2066late\u2069",
};
// Of those, refused in stored text only: searched for, they find nothing (a value stored before
// they were refused can still be found).
const std::vector<std::string> kRefusedWhenStored = {"Ab\u009b2Jcd", "Line\u2028Sep",
                                                     "Evil\u202eecilop", "Iso\u2066late\u2069"};

std::string JsonString(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (byte < 0x20) {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\u%04x", byte);
      out += escaped;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

class Hostile : public ::testing::Test {
 protected:
  void SetUp() override { schema_ = schema(); }
  void TearDown() override {
    EXPECT_EQ(schema(), schema_) << "the schema changed";
    EXPECT_EQ(test::IntegrityCheck(db_), "ok");
    const auto counts = CountRegistry(db_).value();
    EXPECT_GE(counts.pincodes_active, 19159);
    EXPECT_GE(counts.offices, 154874);
  }
  std::string schema() {
    Statement s = db_.prepare(
        "SELECT group_concat(name, ',') FROM (SELECT name FROM "
        "sqlite_master ORDER BY name)");
    s.step();
    return s.getText(0);
  }

  TempDir dir_;
  Connection db_ = test::OpenExisting(test::CopyOfSeeded(dir_));
  std::string schema_;
};

PostOffice OfficeOf(const std::string& text) {
  return {.name = text,
          .branch_type = text,
          .delivery = text,
          .division = text,
          .region = text,
          .circle = text,
          .district = text,
          .state = text,
          .taluk = text};
}

TEST_F(Hostile, OfficeFieldsAndSearch) {
  std::uint32_t pincode = 990000;
  for (const std::string& text : kAccepted) {
    ++pincode;
    const auto added = AddPincode(db_, Pincode(pincode), {OfficeOf(text)});
    ASSERT_TRUE(added.ok()) << text << ": " << added.error().message;
    const PostOffice office = LookupPincode(db_, Pincode(pincode)).value().offices.at(0);
    EXPECT_EQ(office.name, text);
    EXPECT_EQ(office.branch_type, text);
    EXPECT_EQ(office.delivery, text);
    EXPECT_EQ(office.division, text);
    EXPECT_EQ(office.region, text);
    EXPECT_EQ(office.circle, text);
    EXPECT_EQ(office.district, text);
    EXPECT_EQ(office.state, text);
    EXPECT_EQ(office.taluk, text);
    for (const SearchQuery& query : {SearchQuery{.name_prefix = text},
                                     SearchQuery{.district = text}, SearchQuery{.state = text}}) {
      const auto page = Search(db_, query);
      ASSERT_TRUE(page.ok()) << text << ": " << page.error().message;
      ASSERT_EQ(page->total, 1) << text;
      EXPECT_EQ(page->hits.at(0).office.name, text);
    }
  }
  // A LIKE wildcard is an ordinary character in a prefix.
  EXPECT_EQ(Search(db_, {.name_prefix = "%"}).value().total, 0);
  EXPECT_EQ(Search(db_, {.name_prefix = "_"}).value().total, 0);

  for (const std::string& text : kRejected) {
    for (std::string PostOffice::*field :
         {&PostOffice::name, &PostOffice::division, &PostOffice::region, &PostOffice::circle,
          &PostOffice::district, &PostOffice::state}) {
      PostOffice office = OfficeOf("ok");
      office.*field = text;
      const auto added = AddPincode(db_, Pincode(998000), {office});
      ASSERT_FALSE(added.ok());
      EXPECT_EQ(added.error().code, ErrorCode::kInvalid);
    }
    for (std::optional<std::string> PostOffice::*field :
         {&PostOffice::branch_type, &PostOffice::delivery, &PostOffice::taluk}) {
      PostOffice office = OfficeOf("ok");
      office.*field = text;
      EXPECT_EQ(AddPincode(db_, Pincode(998000), {office}).error().code, ErrorCode::kInvalid);
    }
    const bool searchable = std::find(kRefusedWhenStored.begin(), kRefusedWhenStored.end(), text) !=
                            kRefusedWhenStored.end();
    for (const SearchQuery& query : {SearchQuery{.name_prefix = text},
                                     SearchQuery{.district = text}, SearchQuery{.state = text}}) {
      const auto page = Search(db_, query);
      if (searchable) {
        ASSERT_TRUE(page.ok()) << page.error().message;
        EXPECT_EQ(page->total, 0);
      } else {
        EXPECT_EQ(page.error().code, ErrorCode::kInvalid);
      }
    }
  }
  EXPECT_EQ(LookupPincode(db_, Pincode(998000)).error().code, ErrorCode::kNotFound);
}

// A name too long is said in characters as well as bytes: "200 bytes" is about 66 Devanagari
// letters, which a clerk counting letters could not tell.
TEST_F(Hostile, ANameTooLongIsSaidInCharactersAndBytes) {
  std::string hindi;
  for (int i = 0; i < 80; ++i) hindi += "\u0915";  // क, 3 bytes
  const auto added = AddPincode(db_, Pincode(998000), {OfficeOf(hindi)});
  ASSERT_FALSE(added.ok());
  EXPECT_EQ(added.error().code, ErrorCode::kInvalid);
  EXPECT_NE(added.error().message.find("240 bytes long in UTF-8 (80 characters)"),
            std::string::npos)
      << added.error().message;
}

// A name of spaces and invisible characters only would be stored as one nobody can see or type.
TEST_F(Hostile, InvisibleTextIsBlank) {
  for (const std::string& text : {std::string("\u200b"), std::string("\u00a0"),
                                  std::string("\ufeff"), std::string(" \u3000 \u2007"),
                                  std::string("\u2060\u200d\u00ad"), std::string("\u202f\u3164")}) {
    EXPECT_TRUE(IsBlank(text)) << text;
    for (std::string PostOffice::*field : {&PostOffice::name, &PostOffice::district}) {
      PostOffice office = OfficeOf("ok");
      office.*field = text;
      const auto added = AddPincode(db_, Pincode(998000), {office});
      ASSERT_FALSE(added.ok()) << text;
      EXPECT_EQ(added.error().code, ErrorCode::kInvalid);
      EXPECT_NE(added.error().message.find("is blank"), std::string::npos) << added.error().message;
    }
    const SortPlan plan{"ok", text, "", {{"1", "ok"}}};
    EXPECT_EQ(SavePlan(db_, plan).error().code, ErrorCode::kInvalid) << text;
  }
  // Visible text with invisible characters in it is text (ZWJ and ZWNJ shape Indic scripts).
  for (const std::string& text : {std::string("a\u200b"), std::string("\u0915\u094d\u200d"),
                                  std::string("\u00a0x\u00a0"), std::string("0")}) {
    EXPECT_FALSE(IsBlank(text)) << text;
  }
  EXPECT_FALSE(IsBlank("\xff"));  // invalid UTF-8 is refused as such, not as blank
  EXPECT_EQ(LookupPincode(db_, Pincode(998000)).error().code, ErrorCode::kNotFound);
}

TEST_F(Hostile, SortPlanNamesBinsAndCsv) {
  for (const std::string& text : kAccepted) {
    // A name or bin must read as what it is (no space at an end), and a plan name must be a
    // path segment a URL can carry as it is (test_sort_plan: NamesAndBinsMustReadAsWhatTheyAre).
    const bool reads_as_is = text.front() != ' ' && text.back() != ' ';
    const bool url_safe = text.find_first_of("/?#%\\+&=") == std::string::npos;
    const std::string name = reads_as_is && url_safe ? text : "plan";
    const std::string bin = reads_as_is ? text : "bin";
    const SortPlan plan{name, bin, text, {{"1", bin}, {"22", "plain"}}};
    ASSERT_TRUE(SavePlan(db_, plan).ok()) << text;
    const SortPlan stored = GetPlan(db_, name).value();
    EXPECT_EQ(stored.name, name);
    EXPECT_EQ(stored.fallback_bin, bin);
    EXPECT_EQ(stored.description, text);
    EXPECT_EQ(stored.rules.at(0).bin, bin);
    EXPECT_EQ(Route(db_, Pincode(110001), name).value().bin, bin);
    const auto parsed = ParsePlanCsv(name, PlanToCsv(plan));
    ASSERT_TRUE(parsed.ok()) << text << ": " << parsed.error().message;
    EXPECT_EQ(parsed->rules, plan.rules);
    EXPECT_EQ(parsed->fallback_bin, bin);
    EXPECT_TRUE(DeletePlan(db_, name).ok());
    if (!reads_as_is || !url_safe) {
      EXPECT_EQ(SavePlan(db_, SortPlan{text, "bin", "", {{"1", "ok"}}}).error().code,
                ErrorCode::kInvalid)
          << text;
    }
  }
  for (const std::string& text : kRejected) {
    const SortPlan good{"ok", "ok", "", {{"1", "ok"}}};
    SortPlan plan = good;
    plan.name = text;
    EXPECT_EQ(SavePlan(db_, plan).error().code, ErrorCode::kInvalid);
    plan = good;
    plan.fallback_bin = text;
    EXPECT_EQ(SavePlan(db_, plan).error().code, ErrorCode::kInvalid);
    plan = good;
    plan.description = text;
    EXPECT_EQ(SavePlan(db_, plan).error().code, ErrorCode::kInvalid);
    plan = good;
    plan.rules[0].bin = text;
    EXPECT_EQ(SavePlan(db_, plan).error().code, ErrorCode::kInvalid);
    plan = good;
    plan.rules[0].prefix = text;
    EXPECT_EQ(SavePlan(db_, plan).error().code, ErrorCode::kInvalid);
    EXPECT_EQ(Route(db_, Pincode(110001), text).error().code, ErrorCode::kNotFound);
    EXPECT_EQ(GetPlan(db_, text).error().code, ErrorCode::kNotFound);
    EXPECT_FALSE(ParsePlanCsv("x", "prefix,bin\n*," + CsvField(text) + "\n").ok());
  }
  EXPECT_EQ(ListPlans(db_).value(), std::vector<std::string>{"default"});
}

TEST_F(Hostile, TokenLabelsSecretsAndScanJson) {
  for (const std::string& text : kAccepted) {
    const auto token = CreateToken(db_, Role::kScanner, text);
    ASSERT_TRUE(token.ok()) << text;
    EXPECT_EQ(token->info.label, text);
    EXPECT_EQ(VerifyToken(db_, token->secret).value().label, text);
    EXPECT_EQ(VerifyToken(db_, text).error().code, ErrorCode::kUnauthorized);
  }
  for (const std::string& text : kRejected) {
    EXPECT_EQ(CreateToken(db_, Role::kAdmin, text).error().code, ErrorCode::kInvalid);
    EXPECT_EQ(VerifyToken(db_, text).error().code, ErrorCode::kUnauthorized);
    EXPECT_EQ(VerifyToken(db_, "pt_1_" + text).error().code, ErrorCode::kUnauthorized);
  }
  const auto labels = ListTokens(db_).value();
  ASSERT_EQ(labels.size(), kAccepted.size());
  for (std::size_t i = 0; i < labels.size(); ++i) EXPECT_EQ(labels[i].label, kAccepted[i]);

  std::vector<std::string> all = kAccepted;
  all.insert(all.end(), kRejected.begin(), kRejected.end());
  for (const std::string& text : all) {
    // As a JSON string value every text is fine (valid UTF-8 apart), and comes back verbatim.
    const std::string json = "{\"read\":" + JsonString(text) + "}";
    const auto id = AppendScan(db_, {.image_bytes = 10, .result_json = json});
    if (text.find('\xff') != std::string::npos || text.find('\xc0') != std::string::npos) {
      continue;  // SQLite's json_valid does not check UTF-8; either answer is safe
    }
    ASSERT_TRUE(id.ok()) << id.error().message;
    EXPECT_EQ(RecentScans(db_, 1).value().at(0).result_json, json);
    // Raw, it is not JSON: rejected.
    EXPECT_EQ(AppendScan(db_, {.result_json = text}).error().code, ErrorCode::kInvalid) << text;
  }
}

TEST_F(Hostile, ImportedCsvFields) {
  std::string csv =
      "officename,pincode,officeType,Deliverystatus,divisionname,regionname,circlename,Taluk,"
      "Districtname,statename\n";
  std::uint32_t pincode = 997000;
  for (const std::string& text : kAccepted) {
    const std::string f = CsvField(text);
    csv += f + "," + std::to_string(++pincode);
    for (int column = 0; column < 8; ++column) csv += "," + f;
    csv += "\n";
  }
  for (const std::string& text : kRejected) {
    const std::string f = CsvField(text);
    csv += f + ",996000,BO,Delivery,D,R,C,T,X,S\n";
    csv += "Office,996001,BO,Delivery,D,R,C,T," + f + ",S\n";
  }
  const auto report = ImportDirectoryCsv(db_, csv);
  ASSERT_TRUE(report.ok()) << report.error().message;
  EXPECT_EQ(report->pincodes_added.size(), kAccepted.size());
  EXPECT_EQ(report->problems.size(), 2 * kRejected.size());
  pincode = 997000;
  for (const std::string& text : kAccepted) {
    const auto record = LookupPincode(db_, Pincode(++pincode)).value();
    ASSERT_EQ(record.offices.size(), 1u);
    // The importer trims surrounding spaces of CSV fields; everything else is verbatim.
    const std::string expected(text.find_first_not_of(' ') == 0 ? text
                                                                : text.substr(2, text.size() - 4));
    EXPECT_EQ(record.offices[0].name, expected);
    EXPECT_EQ(record.offices[0].district, expected);
    EXPECT_EQ(record.offices[0].taluk, expected);
  }
  EXPECT_EQ(LookupPincode(db_, Pincode(996000)).error().code, ErrorCode::kNotFound);
}

// A NUL in a data row is that row's problem: a check for binary and UTF-16 files once refused the
// whole file for a NUL anywhere in its first 4 KiB.
TEST_F(Hostile, ANulInADataRowRefusesThatRowNotTheFile) {
  const std::string header =
      "officename,pincode,officeType,Deliverystatus,divisionname,regionname,circlename,Taluk,"
      "Districtname,statename\n";
  const std::string csv = header + std::string("Nul\0Office,995001,BO,Delivery,D,R,C,T,X,S\n", 42) +
                          "Good Office,995002,BO,Delivery,D,R,C,T,X,S\n";
  const auto report = ImportDirectoryCsv(db_, csv);
  ASSERT_TRUE(report.ok()) << report.error().message;
  EXPECT_EQ(report->problems.size(), 1U);
  EXPECT_EQ(LookupPincode(db_, Pincode(995001)).error().code, ErrorCode::kNotFound);
  EXPECT_TRUE(LookupPincode(db_, Pincode(995002)).ok());
}

}  // namespace
}  // namespace pintag::db
