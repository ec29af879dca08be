// The India Post CSV importer: both layouts, idempotence, bad rows, --strict, the CLI.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>

#include "db_test_util.hpp"
#include "pintag/codec/key_allocation.hpp"
#include "pintag/db/importer.hpp"
#include "pintag/db/registry.hpp"

namespace pintag::db {
namespace {

using test::TempDir;

// The newer layout, with CRLF line ends, a BOM, quoting (a comma and a doubled quote inside
// quotes), an office of a seeded pincode (its " S.O" suffix dropped, it matches the seed's name
// and fills in the branch type) and two new pincodes.
const std::string kNewerCsv =
    "\xEF\xBB\xBF"
    "circlename,regionname,divisionname,officename,pincode,officetype,delivery,district,statename,"
    "latitude,longitude\r\n"
    "Delhi Circle,Delhi,New Delhi Central,Connaught Place S.O,110001,SO,Delivery,Central Delhi,"
    "Delhi,28.6315,77.2167\r\n"
    "Army Postal Service,APS,APS,\"Camp \"\"Alpha\"\", North\",999011,BO,Non Delivery,APS,APS,NA,"
    "NA\r\n"
    "Army Postal Service,APS,APS,Camp Beta B.O,999012,BO,Delivery,APS,APS,,\r\n"
    "Army Postal Service,APS,APS,Camp Gamma H.O,999012,HO,Delivery,APS,APS,12.5,-77.25\r\n";

// The older layout: column names in their published capitalisation.
const std::string kOlderCsv =
    "officename,pincode,officeType,Deliverystatus,divisionname,regionname,circlename,Taluk,"
    "Districtname,statename\n"
    "Bengali Market S.O,110001,SO,Delivery,New Delhi Central,Delhi,Delhi,New Delhi,Central "
    "Delhi,Delhi\n"
    "Zeta Camp B.O,999021,B.O,Delivery,APS,APS,Army Postal Service,Zeta Taluk,APS,APS\n";

const std::string kNewerHeader =
    "circlename,regionname,divisionname,officename,pincode,officetype,delivery,district,statename,"
    "latitude,longitude\n";
const std::string kOlderHeader =
    "officename,pincode,officeType,Deliverystatus,divisionname,regionname,circlename,Taluk,"
    "Districtname,statename\n";

class Importer : public ::testing::Test {
 protected:
  std::vector<KeyRow> keys() { return ListKeys(db_).value(); }
  RegistryCounts counts() { return CountRegistry(db_).value(); }

  TempDir dir_;
  std::string path_ = test::CopyOfSeeded(dir_);
  Connection db_ = test::OpenExisting(path_);
};

TEST_F(Importer, ReadsTheNewerLayoutAndIsIdempotent) {
  const auto keys_before = keys();
  const auto report = ImportDirectoryCsv(db_, kNewerCsv);
  ASSERT_TRUE(report.ok()) << report.error().message;
  EXPECT_EQ(report->layout, CsvLayout::kNewer);
  EXPECT_TRUE(report->applied);
  EXPECT_EQ(report->rows, 4);
  ASSERT_TRUE(report->problems.empty()) << report->problems.front().message;
  EXPECT_EQ(report->offices_added, 3);
  EXPECT_EQ(report->offices_updated, 1);  // Connaught Place gains type, delivery, position
  ASSERT_EQ(report->pincodes_added.size(), 2u);

  // New pincodes get the keys probing finds past every existing key.
  std::vector<TagKey> taken;
  taken.reserve(keys_before.size());
  for (const KeyRow& row : keys_before) taken.push_back(row.key);
  KeyAllocator allocator(taken);
  EXPECT_EQ(report->pincodes_added[0].first, Pincode(999011));
  EXPECT_EQ(report->pincodes_added[0].second, *allocator.allocate(Pincode(999011)));
  EXPECT_EQ(report->pincodes_added[1].first, Pincode(999012));
  EXPECT_EQ(report->pincodes_added[1].second, *allocator.allocate(Pincode(999012)));

  const auto delhi = LookupPincode(db_, Pincode(110001)).value();
  EXPECT_EQ(delhi.offices.size(), 21u);  // updated in place, not duplicated
  bool found = false;
  for (const PostOffice& office : delhi.offices) {
    if (office.name != "Connaught Place") continue;
    found = true;
    EXPECT_EQ(office.branch_type, "SO");
    EXPECT_EQ(office.delivery, "Delivery");
    ASSERT_TRUE(office.latitude.has_value());
    EXPECT_DOUBLE_EQ(*office.latitude, 28.6315);
    EXPECT_DOUBLE_EQ(office.longitude.value_or(0), 77.2167);
    EXPECT_EQ(office.circle, "Delhi Circle");
  }
  EXPECT_TRUE(found);
  const auto alpha = LookupPincode(db_, Pincode(999011)).value();
  ASSERT_EQ(alpha.offices.size(), 1u);
  EXPECT_EQ(alpha.offices[0].name, "Camp \"Alpha\", North");
  EXPECT_EQ(alpha.offices[0].delivery, "Non Delivery");
  EXPECT_FALSE(alpha.offices[0].latitude.has_value());  // NA
  const auto beta = LookupPincode(db_, Pincode(999012)).value();
  ASSERT_EQ(beta.offices.size(), 2u);
  EXPECT_EQ(beta.offices[0].name, "Camp Beta");
  EXPECT_EQ(beta.offices[1].name, "Camp Gamma");
  EXPECT_EQ(beta.offices[1].branch_type, "HO");
  EXPECT_DOUBLE_EQ(beta.offices[1].longitude.value_or(0), -77.25);

  // Again: nothing changes.
  const auto after_first = keys();
  const auto counts_first = counts();
  const auto again = ImportDirectoryCsv(db_, kNewerCsv);
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again->offices_added, 0);
  EXPECT_EQ(again->offices_updated, 0);
  EXPECT_EQ(again->offices_unchanged, 4);
  EXPECT_TRUE(again->pincodes_added.empty());
  EXPECT_EQ(counts().offices, counts_first.offices);
  const auto after_second = keys();
  ASSERT_EQ(after_second.size(), after_first.size());
  for (std::size_t i = 0; i < after_first.size(); ++i) {
    EXPECT_EQ(after_second[i].key, after_first[i].key);
  }
}

// A database seeded before the seed was trimmed holds names such as "Connaught Place " (55 in
// all). India Post's file names the office without the space: the import updates that office and
// gives it the trimmed name, instead of adding a second one beside it.
TEST_F(Importer, UpdatesAnOfficeStoredWithASpaceAtAnEndInsteadOfAddingIt) {
  const std::int64_t id =
      db_.queryInt64("SELECT id FROM offices WHERE pincode = 110001 AND name = 'Connaught Place'");
  db_.execute("UPDATE offices SET name = 'Connaught Place ' WHERE id = " + std::to_string(id));
  const auto before = LookupPincode(db_, Pincode(110001)).value();
  const auto report = ImportDirectoryCsv(db_, kNewerCsv);
  ASSERT_TRUE(report.ok()) << report.error().message;
  EXPECT_EQ(report->offices_added, 3);  // the three offices of the two new pincodes
  EXPECT_EQ(report->offices_updated, 1);
  const auto delhi = LookupPincode(db_, Pincode(110001)).value();
  EXPECT_EQ(delhi.offices.size(), before.offices.size());
  int named = 0;
  for (const PostOffice& office : delhi.offices) {
    EXPECT_NE(office.name, "Connaught Place ");
    if (office.name != "Connaught Place") continue;
    ++named;
    EXPECT_EQ(office.id, id);  // the same row, renamed
    EXPECT_EQ(office.branch_type, "SO");
  }
  EXPECT_EQ(named, 1);

  // The name's change alone is an update too: with everything else as imported, renaming it back
  // and importing again reports one office updated, none added.
  db_.execute(
      "UPDATE offices SET name = 'Connaught Place ' WHERE pincode = 110001 AND "
      "name = 'Connaught Place'");
  const auto again = ImportDirectoryCsv(db_, kNewerCsv);
  ASSERT_TRUE(again.ok()) << again.error().message;
  EXPECT_EQ(again->offices_added, 0);
  EXPECT_EQ(again->offices_updated, 1);
  EXPECT_EQ(again->offices_unchanged, 3);
  EXPECT_EQ(LookupPincode(db_, Pincode(110001)).value().offices.size(), before.offices.size());
}

// A database seeded before the seed was trimmed that had an India Post import since holds an
// office twice, as "Connaught Place " from the seed and "Connaught Place" from the import. The
// next import of it folds the spaced twin into the other.
TEST_F(Importer, FoldsATwinStoredWithASpaceAtAnEndIntoTheOffice) {
  db_.execute(
      "INSERT INTO offices (pincode, name, division, region, circle, district, state, source, "
      "updated_at) SELECT pincode, name || ' ', division, region, circle, district, state, "
      "source, updated_at FROM offices WHERE pincode = 110001 AND name = 'Connaught Place'");
  const std::int64_t id =
      db_.queryInt64("SELECT id FROM offices WHERE pincode = 110001 AND name = 'Connaught Place'");
  const auto before = LookupPincode(db_, Pincode(110001)).value();
  const auto report = ImportDirectoryCsv(db_, kNewerCsv);
  ASSERT_TRUE(report.ok()) << report.error().message;
  EXPECT_EQ(report->offices_added, 3);
  EXPECT_EQ(report->offices_updated, 1);
  const auto delhi = LookupPincode(db_, Pincode(110001)).value();
  EXPECT_EQ(delhi.offices.size(), before.offices.size() - 1);
  EXPECT_EQ(db_.queryInt64("SELECT count(*) FROM offices WHERE pincode = 110001 AND "
                           "trim(name) = 'Connaught Place'"),
            1);
  EXPECT_EQ(
      db_.queryInt64("SELECT branch_type = 'SO' FROM offices WHERE id = " + std::to_string(id)), 1);
}

// The newer layout types sub offices PO but still names them "... SO", "... S.O" or "... S.O.":
// the suffix goes, so each row fills in its seeded office instead of adding "Connaught Place SO"
// beside it.
TEST_F(Importer, APostOfficeNamedAsASubOfficeMatchesItsSeededName) {
  const std::string place = "Delhi Circle,Delhi Region,New Delhi Central,";
  const std::string csv =
      kNewerHeader + place +
      "Connaught Place SO,110001,PO,Non Delivery,NEW DELHI,DELHI,28.63,77.21\n" + place +
      "Janpath S.O,110001,PO,Delivery,NEW DELHI,DELHI,NA,NA\n" + place +
      "Krishi Bhawan S.O.,110001,PO,Delivery,NEW DELHI,DELHI,NA,NA\n" + place +
      "Rail Bhawan P.O,110001,PO,Delivery,NEW DELHI,DELHI,NA,NA\n" + place +
      // A branch office whose name says SO: not its type's suffix, kept.
      "Shastri Bhawan SO,110001,BO,Delivery,NEW DELHI,DELHI,NA,NA\n";
  const std::size_t offices_before = LookupPincode(db_, Pincode(110001)).value().offices.size();
  const auto report = ImportDirectoryCsv(db_, csv);
  ASSERT_TRUE(report.ok()) << report.error().message;
  ASSERT_TRUE(report->problems.empty()) << report->problems.front().message;
  EXPECT_EQ(report->offices_updated, 4);
  EXPECT_EQ(report->offices_added, 1);
  const auto delhi = LookupPincode(db_, Pincode(110001)).value();
  EXPECT_EQ(delhi.offices.size(), offices_before + 1);
  std::map<std::string, std::optional<std::string>> type_of;
  for (const PostOffice& office : delhi.offices) type_of[office.name] = office.branch_type;
  for (const char* name : {"Connaught Place", "Janpath", "Krishi Bhawan", "Rail Bhawan"}) {
    EXPECT_EQ(type_of[name], "PO") << name;
  }
  EXPECT_EQ(type_of.count("Connaught Place SO"), 0u);
  EXPECT_EQ(type_of["Shastri Bhawan SO"], "BO");
}

// 22 seeded names keep a type suffix ("Dumrawan SO" of 805132). India Post's "Dumrawan S.O"
// loses it on import, and was added beside the seeded office as a second one.
TEST_F(Importer, ASeededNameThatKeptItsSuffixIsTheOfficeAnImportNames) {
  const auto before = LookupPincode(db_, Pincode(805132)).value();
  ASSERT_EQ(std::count_if(before.offices.begin(), before.offices.end(),
                          [](const PostOffice& o) { return o.name == "Dumrawan SO"; }),
            1);
  const std::string csv = kOlderHeader +
                          "Dumrawan S.O,805132,S.O,Delivery,Nawadha,Patna HQ,Bihar,Nawada,"
                          "Nawada,Bihar\n";
  const auto report = ImportDirectoryCsv(db_, csv);
  ASSERT_TRUE(report.ok()) << report.error().message;
  EXPECT_EQ(report->offices_added, 0);
  EXPECT_EQ(report->offices_updated, 1);
  const auto after = LookupPincode(db_, Pincode(805132)).value();
  EXPECT_EQ(after.offices.size(), before.offices.size());
  const auto dumrawan = std::find_if(after.offices.begin(), after.offices.end(),
                                     [](const PostOffice& o) { return o.name == "Dumrawan"; });
  ASSERT_NE(dumrawan, after.offices.end());
  EXPECT_EQ(dumrawan->branch_type, "SO");
  EXPECT_EQ(dumrawan->taluk, "Nawada");

  const auto again = ImportDirectoryCsv(db_, csv);
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again->offices_unchanged, 1);
}

// India Post writes NA for what it does not know. In an optional field that is unknown; in a
// required one (a place a label prints) it is a bad row, as an empty field is.
TEST_F(Importer, ARequiredFieldThatSaysNaIsABadRow) {
  const std::string csv = kOlderHeader +
                          "Alpha B.O,999061,BO,Delivery,APS,APS,APS,NA,NA,APS\n"   // district
                          "Beta B.O,999062,BO,Delivery,APS,APS,APS,T,APS,n/a\n"    // state
                          "Gamma B.O,999063,BO,Delivery,Null,APS,APS,T,APS,APS\n"  // division
                          "NA,999064,BO,Delivery,APS,APS,APS,T,APS,APS\n"          // office name
                          "Delta B.O,999065,BO,NA,APS,APS,APS,NA,APS,APS\n";       // optional NA
  const auto report = ImportDirectoryCsv(db_, csv);
  ASSERT_TRUE(report.ok()) << report.error().message;
  ASSERT_EQ(report->problems.size(), 4u);
  const std::pair<std::int64_t, const char*> expected[] = {
      {2, "district is 'NA', which means unknown; it is required"},
      {3, "state is 'n/a', which means unknown; it is required"},
      {4, "division is 'Null', which means unknown; it is required"},
      {5, "office name is 'NA', which means unknown; it is required"}};
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(report->problems[i].line, expected[i].first);
    EXPECT_EQ(report->problems[i].message, expected[i].second);
  }
  ASSERT_EQ(report->pincodes_added.size(), 1u);
  const PincodeRecord delta = LookupPincode(db_, Pincode(999065)).value();
  ASSERT_EQ(delta.offices.size(), 1u);
  EXPECT_FALSE(delta.offices[0].delivery.has_value());
  EXPECT_FALSE(delta.offices[0].taluk.has_value());
  EXPECT_EQ(LookupPincode(db_, Pincode(999061)).error().code, ErrorCode::kNotFound);
}

// Fields are trimmed of Unicode spaces as of ASCII ones (U+00A0 from a spreadsheet, U+3000,
// zero-width spaces): a no-break space after "S.O" no longer keeps the suffix, nor adds an office.
TEST_F(Importer, UnicodeSpacesAroundAFieldAreTrimmed) {
  const std::string nbsp = "\u00a0";
  const std::string csv =
      kNewerHeader + "Delhi Circle,Delhi Region,New Delhi Central,Connaught Place S.O" + nbsp +
      ",110001" + nbsp + ",SO,Delivery,Central Delhi" + nbsp + ",Delhi,NA,NA\n" + "APS,APS,APS," +
      nbsp + "Nbsp" + nbsp + "Camp\u200b,999071,BO,Delivery,\u3000Apsdist," + "APS\ufeff,NA,NA\n" +
      // A variation selector at the end belongs to the emoji before it: kept.
      "APS,APS,APS,Heart \u2764\ufe0f,999072,BO,Delivery,APS,APS,NA,NA\n" +
      "APS,APS,APS,Blank District,999073,BO,Delivery," + nbsp + nbsp + ",APS,NA,NA\n";
  const std::size_t offices_before = LookupPincode(db_, Pincode(110001)).value().offices.size();
  const auto report = ImportDirectoryCsv(db_, csv);
  ASSERT_TRUE(report.ok()) << report.error().message;
  ASSERT_EQ(report->problems.size(), 1u);
  EXPECT_EQ(report->problems[0].line, 5);
  EXPECT_EQ(report->problems[0].message, "district is empty");
  EXPECT_EQ(report->offices_updated, 1);
  EXPECT_EQ(LookupPincode(db_, Pincode(110001)).value().offices.size(), offices_before);
  const PincodeRecord camp = LookupPincode(db_, Pincode(999071)).value();
  ASSERT_EQ(camp.offices.size(), 1u);
  EXPECT_EQ(camp.offices[0].name, "Nbsp" + nbsp + "Camp");  // inside, it stays
  EXPECT_EQ(camp.offices[0].district, "Apsdist");
  EXPECT_EQ(camp.offices[0].state, "APS");
  EXPECT_EQ(LookupPincode(db_, Pincode(999072)).value().offices.at(0).name, "Heart \u2764\ufe0f");
}

// A spreadsheet may write a coordinate with its sign: "+77.5" is 77.5; "+-5" is still not a number.
TEST_F(Importer, ACoordinateWithALeadingPlusIsANumber) {
  const std::string csv = kNewerHeader +
                          "APS,APS,APS,Plus Camp,999081,BO,Delivery,APS,APS,+12.5,+77.5\n"
                          "APS,APS,APS,Point Camp,999082,BO,Delivery,APS,APS,+.5,77\n"
                          "APS,APS,APS,Twice Camp,999083,BO,Delivery,APS,APS,+-5,77\n"
                          "APS,APS,APS,Bare Camp,999084,BO,Delivery,APS,APS,12,+\n";
  const auto report = ImportDirectoryCsv(db_, csv);
  ASSERT_TRUE(report.ok()) << report.error().message;
  ASSERT_EQ(report->problems.size(), 2u);
  EXPECT_EQ(report->problems[0].message, "latitude '+-5' is not a number");
  EXPECT_EQ(report->problems[1].message, "longitude '+' is not a number");
  const PostOffice plus = LookupPincode(db_, Pincode(999081)).value().offices.at(0);
  EXPECT_DOUBLE_EQ(plus.latitude.value_or(0), 12.5);
  EXPECT_DOUBLE_EQ(plus.longitude.value_or(0), 77.5);
  EXPECT_DOUBLE_EQ(LookupPincode(db_, Pincode(999082)).value().offices.at(0).latitude.value_or(0),
                   0.5);
}

TEST_F(Importer, ReadsTheOlderLayout) {
  const auto report = ImportDirectoryCsv(db_, kOlderCsv);
  ASSERT_TRUE(report.ok()) << report.error().message;
  EXPECT_EQ(report->layout, CsvLayout::kOlder);
  ASSERT_TRUE(report->problems.empty()) << report->problems.front().message;
  EXPECT_EQ(report->rows, 2);
  EXPECT_EQ(report->offices_added, 1);
  EXPECT_EQ(report->offices_updated, 1);
  ASSERT_EQ(report->pincodes_added.size(), 1u);
  const auto zeta = LookupPincode(db_, Pincode(999021)).value();
  ASSERT_EQ(zeta.offices.size(), 1u);
  EXPECT_EQ(zeta.offices[0].name, "Zeta Camp");
  EXPECT_EQ(zeta.offices[0].branch_type, "BO");  // "B.O" normalised
  EXPECT_EQ(zeta.offices[0].taluk, "Zeta Taluk");
  EXPECT_EQ(zeta.offices[0].circle, "Army Postal Service");
  EXPECT_EQ(zeta.key, report->pincodes_added[0].second);
  const auto delhi = LookupPincode(db_, Pincode(110001)).value();
  EXPECT_EQ(delhi.offices.front().name, "Bengali Market");
  EXPECT_EQ(delhi.offices.front().branch_type, "SO");
  EXPECT_EQ(delhi.offices.front().taluk, "New Delhi");
  EXPECT_EQ(delhi.offices.size(), 21u);

  const auto again = ImportDirectoryCsv(db_, kOlderCsv);
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again->offices_unchanged, 2);
  EXPECT_TRUE(again->pincodes_added.empty());
}

// Line numbers count physical lines: the quoted line break in row 3 moves later rows down.
const std::string kMalformedCsv =
    "officename,pincode,officeType,Deliverystatus,divisionname,regionname,circlename,Taluk,"
    "Districtname,statename\n"                                   // line 1
    "Good One B.O,999031,BO,Delivery,APS,APS,APS,T,APS,APS\n"    // line 2
    "\"Two\nLines\",999032,BO,Delivery,APS,APS,APS,T,APS,APS\n"  // 3-4
    "Short Row,999033,BO\n"                                      // line 5
    "Bad Pin,99903,BO,Delivery,APS,APS,APS,T,APS,APS\n"          // line 6
    "Bad \"quote,999034,BO,Delivery,APS,APS,APS,T,APS,APS\n"     // line 7
    "Empty District,999035,BO,Delivery,APS,APS,APS,T,,APS\n"     // line 8
    "Good Two B.O,999036,BO,Delivery,APS,APS,APS,T,APS,APS\n";   // line 9

TEST_F(Importer, ReportsMalformedRowsWithLineNumbersAndSkipsThem) {
  const auto report = ImportDirectoryCsv(db_, kMalformedCsv);
  ASSERT_TRUE(report.ok()) << report.error().message;
  EXPECT_TRUE(report->applied);
  EXPECT_EQ(report->rows, 7);
  ASSERT_EQ(report->problems.size(), 5u);
  EXPECT_EQ(report->problems[0].line, 3);  // a line break in a name
  EXPECT_NE(report->problems[0].message.find("lines 3-4 were read as one row"), std::string::npos)
      << report->problems[0].message;
  EXPECT_EQ(report->problems[1].line, 5);
  EXPECT_NE(report->problems[1].message.find("expected 10 fields, got 3"), std::string::npos);
  EXPECT_EQ(report->problems[2].line, 6);
  EXPECT_NE(report->problems[2].message.find("pincode"), std::string::npos);
  EXPECT_EQ(report->problems[3].line, 7);
  EXPECT_NE(report->problems[3].message.find("quote"), std::string::npos);
  EXPECT_EQ(report->problems[4].line, 8);
  EXPECT_NE(report->problems[4].message.find("district"), std::string::npos);
  EXPECT_EQ(report->offices_added, 2);
  ASSERT_EQ(report->pincodes_added.size(), 2u);
  EXPECT_EQ(report->pincodes_added[0].first, Pincode(999031));
  EXPECT_EQ(report->pincodes_added[1].first, Pincode(999036));
}

TEST_F(Importer, StrictRefusesTheWholeFileAndLeavesTheDatabaseUnchanged) {
  const auto keys_before = keys();
  const auto counts_before = counts();
  const std::int64_t data_version = db_.queryInt64("SELECT total_changes()");
  const auto report = ImportDirectoryCsv(db_, kMalformedCsv, {.strict = true});
  ASSERT_TRUE(report.ok()) << report.error().message;
  EXPECT_FALSE(report->applied);
  EXPECT_EQ(report->problems.size(), 5u);
  EXPECT_TRUE(report->pincodes_added.empty());
  EXPECT_EQ(db_.queryInt64("SELECT total_changes()"), data_version);
  const auto counts_after = counts();
  EXPECT_EQ(counts_after.offices, counts_before.offices);
  EXPECT_EQ(counts_after.pincodes_active, counts_before.pincodes_active);
  const auto keys_after = keys();
  ASSERT_EQ(keys_after.size(), keys_before.size());
  EXPECT_EQ(LookupPincode(db_, Pincode(999031)).error().code, ErrorCode::kNotFound);
}

TEST_F(Importer, RefusesAnUnknownHeader) {
  const auto report = ImportDirectoryCsv(db_, "pincode,name\n110001,x\n");
  ASSERT_FALSE(report.ok());
  EXPECT_EQ(report.error().code, ErrorCode::kInvalid);
  EXPECT_NE(report.error().message.find("line 1"), std::string::npos);
  EXPECT_EQ(ImportDirectoryCsvFile(db_, dir_.file("missing.csv")).error().code,
            ErrorCode::kNotFound);
}

// A header that lacks a column names the ones it lacks; one that has a column twice (names are
// compared case-insensitively) names it, since which field holds the value cannot be told.
TEST_F(Importer, AHeaderNamesTheColumnsItLacksOrRepeats) {
  const std::string row = "APS,APS,APS,Camp,999091,BO,Delivery,APS,APS,NA,NA\n";
  const auto without_district = ImportDirectoryCsv(
      db_,
      "circlename,regionname,divisionname,officename,pincode,officetype,delivery,statename,"
      "latitude,longitude\n" +
          row);
  ASSERT_FALSE(without_district.ok());
  EXPECT_NE(without_district.error().message.find(
                "line 1: not an All India Pincode Directory header: missing the newer layout's "
                "district ("),
            std::string::npos)
      << without_district.error().message;
  const auto older_without_two = ImportDirectoryCsv(
      db_,
      "officename,pincode,officeType,Deliverystatus,divisionname,regionname,circlename,"
      "statename\nA,999092,BO,Delivery,APS,APS,APS,APS\n");
  ASSERT_FALSE(older_without_two.ok());
  EXPECT_NE(
      older_without_two.error().message.find("missing the older layout's Taluk and Districtname"),
      std::string::npos)
      << older_without_two.error().message;

  const std::int64_t changes = db_.queryInt64("SELECT total_changes()");
  const auto twice = ImportDirectoryCsv(db_,
                                        "circlename,regionname,divisionname,officename,"
                                        "pincode,officetype,delivery,district,statename,"
                                        "latitude,longitude, PINCODE\n"
                                        "APS,APS,APS,Camp,999093,BO,Delivery,APS,APS,NA,NA,"
                                        "999094\n");
  ASSERT_FALSE(twice.ok());
  EXPECT_EQ(twice.error().code, ErrorCode::kInvalid);
  EXPECT_EQ(twice.error().message,
            "line 1: the header has the column pincode 2 times (fields 5 and 12); which one holds "
            "the value cannot be told");
  EXPECT_EQ(db_.queryInt64("SELECT total_changes()"), changes);
  // A column the importer does not read may repeat (a spreadsheet's empty trailing columns).
  const auto extra = ImportDirectoryCsv(db_, kNewerHeader.substr(0, kNewerHeader.size() - 1) +
                                                 ",,\n" + row.substr(0, row.size() - 1) + ",,\n");
  ASSERT_TRUE(extra.ok()) << extra.error().message;
  EXPECT_EQ(extra->offices_added, 1);
}

// A header and nothing else is an import with nothing in it: refused, as an empty file is.
TEST_F(Importer, AHeaderWithoutRowsIsRefused) {
  for (const std::string& csv : {kNewerHeader, kOlderHeader + "\r\n\n"}) {
    const auto report = ImportDirectoryCsv(db_, csv);
    ASSERT_FALSE(report.ok());
    EXPECT_EQ(report.error().code, ErrorCode::kInvalid);
    EXPECT_EQ(report.error().message, "the file has a header and no data rows; nothing to import");
  }
}

TEST_F(Importer, AQuoteNeverClosedRefusesTheWholeFile) {
  // The reader runs to the end of the file inside the quote: the rows after it are not rows.
  const std::string csv =
      "officename,pincode,officeType,Deliverystatus,divisionname,regionname,circlename,Taluk,"
      "Districtname,statename\n"
      "Alpha B.O,999041,BO,Delivery,APS,APS,APS,T,APS,APS\n"
      "\"Beta B.O,999042,BO,Delivery,APS,APS,APS,T,APS,APS\n"
      "Gamma B.O,999043,BO,Delivery,APS,APS,APS,T,APS,APS\n"
      "Delta B.O,999044,BO,Delivery,APS,APS,APS,T,APS,APS\n";
  const std::int64_t changes = db_.queryInt64("SELECT total_changes()");
  const auto report = ImportDirectoryCsv(db_, csv);
  ASSERT_FALSE(report.ok());
  EXPECT_EQ(report.error().code, ErrorCode::kInvalid);
  EXPECT_NE(report.error().message.find("line 3: a quoted field opens here and is never closed"),
            std::string::npos)
      << report.error().message;
  EXPECT_EQ(db_.queryInt64("SELECT total_changes()"), changes);
  EXPECT_EQ(LookupPincode(db_, Pincode(999041)).error().code, ErrorCode::kNotFound);
}

TEST_F(Importer, AnUnbalancedQuoteInAColumnNotReadLosesNoRowUnsaid) {
  // An extra column the importer does not read: one remark opens a quote, a later one closes it.
  // The lines between become one field of row 3, whose other fields are good.
  const std::string header =
      "circlename,regionname,divisionname,officename,pincode,officetype,delivery,district,"
      "statename,latitude,longitude,remarks\n";
  const auto row = [](const std::string& name, int pincode, const std::string& remark) {
    return "APS,APS,APS," + name + "," + std::to_string(pincode) + ",BO,Delivery,APS,APS,,," +
           remark + "\n";
  };
  std::string csv = header + row("Alpha B.O", 999051, "") + row("Beta B.O", 999052, "\"see note");
  for (int i = 0; i < 5; ++i) csv += row("Hidden B.O", 999053 + i, "");
  csv += row("Gamma B.O", 999058, "checked\"") + row("Omega B.O", 999059, "");
  const auto report = ImportDirectoryCsv(db_, csv);
  ASSERT_TRUE(report.ok()) << report.error().message;
  ASSERT_EQ(report->problems.size(), 1u);
  EXPECT_EQ(report->problems[0].line, 3);
  EXPECT_NE(report->problems[0].message.find("lines 3-9 were read as one row"), std::string::npos)
      << report->problems[0].message;
  EXPECT_EQ(report->offices_added, 2);  // Alpha and Omega
  EXPECT_TRUE(LookupPincode(db_, Pincode(999051)).ok());
  EXPECT_TRUE(LookupPincode(db_, Pincode(999059)).ok());
  EXPECT_EQ(LookupPincode(db_, Pincode(999052)).error().code, ErrorCode::kNotFound);

  const auto strict = ImportDirectoryCsv(db_, csv, {.strict = true});
  ASSERT_TRUE(strict.ok());
  EXPECT_FALSE(strict->applied);
}

TEST_F(Importer, LineNumbersCountLoneCarriageReturnsAsLineEnds) {
  // Old Mac line ends, a blank line, and a quoted CR inside a name: bad rows on physical lines
  // 4 and 6.
  std::string csv = kOlderHeader;
  csv.back() = '\r';
  csv += "Good B.O,999061,BO,Delivery,APS,APS,APS,T,APS,APS\r\r";      // lines 2-3
  csv += "Short Row,999062,BO\r";                                      // line 4
  csv += "\"Two\rLines\",999063,BO,Delivery,APS,APS,APS,T,APS,APS\r";  // 5-6
  csv += "Bad Pin,99906,BO,Delivery,APS,APS,APS,T,APS,APS\r";          // line 7
  const auto report = ImportDirectoryCsv(db_, csv);
  ASSERT_TRUE(report.ok()) << report.error().message;
  ASSERT_EQ(report->problems.size(), 3u);
  EXPECT_EQ(report->problems[0].line, 4);
  EXPECT_EQ(report->problems[1].line, 5);
  EXPECT_NE(report->problems[1].message.find("lines 5-6"), std::string::npos);
  EXPECT_EQ(report->problems[2].line, 7);
}

TEST_F(Importer, ThousandsOfBadRowsAreCountedAndTheFirstThousandDescribed) {
  std::string csv = kOlderHeader;
  for (int i = 0; i < 3000; ++i) csv += "a\n";
  csv += "Good B.O,999081,BO,Delivery,APS,APS,APS,T,APS,APS\n";
  const auto report = ImportDirectoryCsv(db_, csv);
  ASSERT_TRUE(report.ok()) << report.error().message;
  EXPECT_EQ(report->bad_rows, 3000);
  ASSERT_EQ(report->problems.size(), kMaxProblemsKept);
  EXPECT_EQ(report->problems.front().line, 2);
  EXPECT_EQ(report->problems.back().line, 1 + static_cast<std::int64_t>(kMaxProblemsKept));
  EXPECT_EQ(report->offices_added, 1);
}

TEST_F(Importer, AFieldQuotedInAMessageIsCutAndItsControlBytesEscaped) {
  const std::string row_start = "APS,APS,APS,Camp B.O,999091,BO,Delivery,APS,APS,";
  const std::string csv = kNewerHeader + row_start + "12.5," + std::string(100000, '7') + "\n" +
                          row_start + "\x1b]0;pwned\x07\x1b[2J28.6,77.2\n";
  const auto parsed = ParseDirectoryCsv(csv);
  ASSERT_TRUE(parsed.ok());
  ASSERT_EQ(parsed->report.problems.size(), 2u);
  const std::string& long_one = parsed->report.problems[0].message;
  EXPECT_LT(long_one.size(), 120u) << long_one;
  EXPECT_NE(long_one.find("longitude '" + std::string(40, '7') + "...' is not a number"),
            std::string::npos)
      << long_one;
  const std::string& escaped = parsed->report.problems[1].message;
  EXPECT_EQ(escaped.find('\x1b'), std::string::npos);
  EXPECT_NE(escaped.find("latitude '\\x1B]0;pwned\\x07\\x1B[2J28.6' is not a number"),
            std::string::npos)
      << escaped;
  const std::string bidi = ParseDirectoryCsv(kNewerHeader + row_start + "12\u202Eabc,77.2\n")
                               ->report.problems.at(0)
                               .message;
  EXPECT_NE(bidi.find("latitude '12\\xE2\\x80\\xAEabc' is not a number"), std::string::npos)
      << bidi;
}

TEST_F(Importer, ARecordSpanningLinesNamesTheQuoteThatHeldTheLineBreak) {
  // The line break is in the name, quoted on line 2; a later field of the record, on line 3, is
  // quoted too.
  const std::string csv = kOlderHeader +
                          "\"Alpha\nB.O\",999111,BO,Delivery,APS,APS,APS,T,APS,\"APS\"\n"
                          "Gamma B.O,999112,BO,Delivery,APS,APS,APS,T,APS,APS\n";
  const auto parsed = ParseDirectoryCsv(csv);
  ASSERT_TRUE(parsed.ok()) << parsed.error().message;
  ASSERT_EQ(parsed->report.problems.size(), 1u);
  EXPECT_NE(parsed->report.problems[0].message.find(
                "lines 2-3 were read as one row: a quoted field opening on line 2"),
            std::string::npos)
      << parsed->report.problems[0].message;
}

TEST_F(Importer, AQuoteNeverClosedIsNamedOnTheLineItOpens) {
  // The record starts on line 2 with a good two-line quoted field; the quote never closed opens on
  // line 3.
  const std::string csv = kOlderHeader +
                          "\"Two\nLines\",999071,BO,Delivery,APS,APS,APS,\"T,APS,APS\n"
                          "Gamma B.O,999072,BO,Delivery,APS,APS,APS,T,APS,APS\n";
  const auto report = ImportDirectoryCsv(db_, csv);
  ASSERT_FALSE(report.ok());
  EXPECT_NE(report.error().message.find("line 3: a quoted field opens here"), std::string::npos)
      << report.error().message;
}

TEST_F(Importer, AnOfficeTwiceInAFileKeepsTheFirstAndAReimportSettles) {
  const std::string header =
      "officename,pincode,officeType,Deliverystatus,divisionname,regionname,circlename,Taluk,"
      "Districtname,statename\n";
  const std::string first = "Alpha B.O,999051,BO,NA,APS,APS,APS,T,Firstpur,APS\n";
  const std::string more = "Alpha B.O,999051,BO,Delivery,APS,APS,APS,T,Firstpur,APS\n";
  const std::string other = "Alpha B.O,999051,BO,Delivery,APS,APS,APS,T,Otherpur,APS\n";
  const std::string csv = header + first + first + more + other;
  const auto report = ImportDirectoryCsv(db_, csv);
  ASSERT_TRUE(report.ok()) << report.error().message;
  EXPECT_EQ(report->rows, 4);
  EXPECT_EQ(report->offices_added, 1);
  // The same row again, and one that only adds what the first lacked: counted, not faults.
  EXPECT_EQ(report->repeated_rows, 2);
  ASSERT_EQ(report->problems.size(), 1u);
  EXPECT_EQ(report->problems[0].line, 5);
  EXPECT_NE(report->problems[0].message.find("is on line 2 too, with other details"),
            std::string::npos)
      << report->problems[0].message;
  const PincodeRecord stored = LookupPincode(db_, Pincode(999051)).value();
  EXPECT_EQ(stored.district, "Firstpur");
  ASSERT_EQ(stored.offices.size(), 1u);
  EXPECT_EQ(stored.offices[0].delivery, "Delivery");  // taken from the row that knew it
  // Imported again, nothing changes: the office is not rewritten back and forth.
  const auto again = ImportDirectoryCsv(db_, csv);
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again->offices_updated, 0);
  EXPECT_EQ(again->offices_unchanged, 1);
  EXPECT_EQ(LookupPincode(db_, Pincode(999051)).value().district, "Firstpur");
}

TEST_F(Importer, NewPincodesProbePastRetiredKeys) {
  // Retire a pincode, then import one whose start slot is that retired key: it must probe on.
  const auto rows = keys();
  Pincode victim = rows.front().pincode;
  TagKey victim_key = rows.front().key;
  std::optional<Pincode> newcomer;
  for (std::uint32_t p = 900000; p <= 999999 && !newcomer; ++p) {
    if (StartSlot(Pincode(p)) == victim_key) newcomer = Pincode(p);
  }
  ASSERT_TRUE(newcomer.has_value());
  ASSERT_TRUE(RetirePincode(db_, victim).ok());
  const std::string csv =
      "officename,pincode,officeType,Deliverystatus,divisionname,regionname,circlename,Taluk,"
      "Districtname,statename\nProbe B.O," +
      newcomer->str() + ",BO,Delivery,APS,APS,APS,T,APS,APS\n";
  const auto report = ImportDirectoryCsv(db_, csv);
  ASSERT_TRUE(report.ok());
  ASSERT_EQ(report->pincodes_added.size(), 1u);
  EXPECT_NE(report->pincodes_added[0].second, victim_key);
  EXPECT_EQ(LookupKey(db_, victim_key).value().pincode, victim);
  EXPECT_EQ(LookupPincode(db_, victim).value().status, PincodeStatus::kRetired);
}

// `pintag import` into a database file that does not exist yet: created, seeded, then imported.
// An import into a database another process is writing waits 5 s for the lock, then gives up.
// It said "pintag: FILE.csv: execute: database is locked", as if the file imported were at fault.
TEST_F(Importer, CommandLineImportIntoALockedDatabaseSaysWhoHoldsItAndImportsNothing) {
  if (test::PintagExe().empty()) GTEST_SKIP() << "no pintag executable in this build";
  const std::string db = dir_.file("locked.db");
  const std::string first = test::WriteFile(dir_.file("older.csv"), kOlderCsv);
  ASSERT_EQ(
      test::RunCommand(test::PintagExe() + " import " + first + " --db " + db + " 2>&1").exit_code,
      0);
  const std::string csv = test::WriteFile(dir_.file("newer.csv"), kNewerCsv);
  Connection other = test::OpenExisting(db);
  other.execute("BEGIN IMMEDIATE");
  const auto locked =
      test::RunCommand(test::PintagExe() + " import " + csv + " --db " + db + " 2>&1");
  other.execute("ROLLBACK");
  EXPECT_EQ(locked.exit_code, 1) << locked.out;
  EXPECT_NE(locked.out.find(db + " is being written by another process"), std::string::npos)
      << locked.out;
  EXPECT_NE(locked.out.find("nothing of " + csv + " was imported"), std::string::npos)
      << locked.out;
  EXPECT_EQ(LookupPincode(other, Pincode(999011)).error().code, ErrorCode::kNotFound);
}

TEST_F(Importer, CommandLineImportCreatesTheDatabaseAndLooksUp) {
  if (test::PintagExe().empty()) GTEST_SKIP() << "no pintag executable in this build";
  const std::string csv = test::WriteFile(dir_.file("newer.csv"), kNewerCsv);
  const std::string db = dir_.file("fresh.db");
  const auto imported =
      test::RunCommand(test::PintagExe() + " import " + csv + " --db " + db + " 2>&1");
  EXPECT_EQ(imported.exit_code, 0) << imported.out;
  EXPECT_NE(imported.out.find("created " + db + " and seeded it"), std::string::npos)
      << imported.out;
  EXPECT_NE(imported.out.find("3 offices added, 1 updated"), std::string::npos) << imported.out;
  EXPECT_NE(imported.out.find(", 2 new pincodes, 0 bad rows skipped"), std::string::npos)
      << imported.out;
  Connection fresh = test::OpenExisting(db);
  EXPECT_EQ(CountRegistry(fresh).value().pincodes_active, 19159 + 2);
  // One of each is said in the singular ("1 rows, 1 offices added, 1 new pincodes" before).
  const std::string one = test::WriteFile(
      dir_.file("one.csv"),
      "circlename,regionname,divisionname,officename,pincode,officetype,delivery,district,"
      "statename,latitude,longitude\n"
      "X Circle,X,X,Testpur S.O,999123,SO,Delivery,Testdist,Teststate,12.0,77.0\n");
  const auto single = test::RunCommand(test::PintagExe() + " import " + one + " --db " + db);
  EXPECT_EQ(single.exit_code, 0) << single.out;
  EXPECT_NE(single.out.find(": 1 row, 1 office added, 0 updated, 0 unchanged, 1 new pincode, "
                            "0 bad rows skipped\n"),
            std::string::npos)
      << single.out;
  const TagKey key = LookupPincode(fresh, Pincode(999011)).value().key;
  const auto by_key = test::RunCommand(test::PintagExe() + " keys lookup --key " +
                                       std::to_string(key.value()) + " --db " + db);
  EXPECT_EQ(by_key.exit_code, 0);
  EXPECT_NE(by_key.out.find("pincode  999011"), std::string::npos) << by_key.out;
  const auto by_pincode = test::RunCommand(test::PintagExe() + " keys lookup 110001 --db " + db);
  EXPECT_NE(by_pincode.out.find("Central Delhi"), std::string::npos) << by_pincode.out;
  EXPECT_NE(
      test::RunCommand(test::PintagExe() + " keys lookup 11000 --db " + db + " 2>&1").exit_code, 0);

  const std::string bad = test::WriteFile(dir_.file("bad.csv"), kMalformedCsv);
  const auto strict =
      test::RunCommand(test::PintagExe() + " import " + bad + " --strict --db " + db + " 2>&1");
  EXPECT_NE(strict.exit_code, 0);
  EXPECT_NE(strict.out.find("bad.csv:5: expected 10 fields, got 3"), std::string::npos)
      << strict.out;
  EXPECT_NE(strict.out.find("nothing imported"), std::string::npos) << strict.out;
  EXPECT_EQ(LookupPincode(fresh, Pincode(999031)).error().code, ErrorCode::kNotFound);
  const auto lenient =
      test::RunCommand(test::PintagExe() + " import " + bad + " --db " + db + " 2>&1");
  EXPECT_EQ(lenient.exit_code, 0) << lenient.out;
  EXPECT_NE(lenient.out.find("bad.csv:3: lines 3-4 were read as one row"), std::string::npos)
      << lenient.out;
  EXPECT_NE(lenient.out.find("5 bad rows skipped"), std::string::npos) << lenient.out;
  EXPECT_TRUE(LookupPincode(fresh, Pincode(999031)).ok());

  // A file none of whose rows can be imported is a failed job, not a success with warnings.
  const std::string all_bad = test::WriteFile(
      dir_.file("all-bad.csv"),
      "officename,pincode,officeType,Deliverystatus,divisionname,regionname,circlename,Taluk,"
      "Districtname,statename\nAlpha B.O,99901,BO,Delivery,APS,APS,APS,T,APS,APS\n");
  const auto none =
      test::RunCommand(test::PintagExe() + " import " + all_bad + " --db " + db + " 2>&1");
  EXPECT_NE(none.exit_code, 0) << none.out;
  EXPECT_NE(none.out.find("its one row could not be imported"), std::string::npos) << none.out;
}

// On a terminal the progress bar is erased before the database is said to be created: the message
// was written onto the bar's line ("...] 100%created fresh.db and seeded it").
TEST_F(Importer, CommandLineImportOnATerminalSaysItCreatedTheDatabaseOnALineOfItsOwn) {
  if (test::PintagExe().empty()) GTEST_SKIP() << "no pintag executable in this build";
  const std::string csv = test::WriteFile(dir_.file("newer.csv"), kNewerCsv);
  const std::string db = dir_.file("fresh.db");
  // script(1) runs the command on a pseudo-terminal and copies what it shows to stdout.
  const auto shown = test::RunCommand("script -qec '" + test::PintagExe() + " import " + csv +
                                      " --db " + db + "' /dev/null < /dev/null");
  EXPECT_EQ(shown.exit_code, 0) << shown.out;
  EXPECT_NE(shown.out.find("parse ["), std::string::npos) << shown.out;  // a terminal: a bar
  // The seconds of seeding are said first, each line on its own (a terminal shows \r\n).
  EXPECT_NE(shown.out.find("\r\033[Kseeding " + db + " from " + SeedSource() +
                           " (a few seconds)...\r\ncreated " + db + " and seeded it"),
            std::string::npos)
      << shown.out;
  EXPECT_EQ(shown.out.find("%created"), std::string::npos) << shown.out;
  EXPECT_EQ(shown.out.find("%seeding"), std::string::npos) << shown.out;
}

// A file that cannot be read leaves no database behind, and says why it cannot be read.
TEST_F(Importer, CommandLineImportOfAMissingFileCreatesNoDatabase) {
  if (test::PintagExe().empty()) GTEST_SKIP() << "no pintag executable in this build";
  const std::string db = dir_.file("never.db");
  const auto missing = test::RunCommand(test::PintagExe() + " import " + dir_.file("nosuch.csv") +
                                        " --db " + db + " 2>&1");
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.out.find("nosuch.csv: No such file or directory"), std::string::npos)
      << missing.out;
  const auto directory = test::RunCommand(test::PintagExe() + " import " + dir_.path().string() +
                                          " --db " + db + " 2>&1");
  EXPECT_NE(directory.exit_code, 0);
  EXPECT_NE(directory.out.find("is a directory"), std::string::npos) << directory.out;
  EXPECT_FALSE(std::filesystem::exists(db));
}

// The newer layout types a sub office PO, not SO. Its pincode's main office (the one labels print
// and the summary's district and state come from) is that sub office, not the branch office
// listed before it; the head office still comes first.
TEST_F(Importer, ANewerLayoutSubOfficeTypedPoIsTheMainOfficeOverABranch) {
  const std::string csv = kNewerHeader +
                          "Test Circle,Test,Test Division,Alpha B.O,999501,BO,Delivery,"
                          "Branchpur,Branch State,NA,NA\n"
                          "Test Circle,Test,Test Division,Beta SO,999501,PO,Delivery,Subpur,"
                          "Sub State,NA,NA\n"
                          "Test Circle,Test,Test Division,Gamma SO,999502,PO,Delivery,Subpur,"
                          "Sub State,NA,NA\n"
                          "Test Circle,Test,Test Division,Delta H.O,999502,HO,Delivery,Headpur,"
                          "Head State,NA,NA\n";
  const auto report = ImportDirectoryCsv(db_, csv);
  ASSERT_TRUE(report.ok()) << report.error().message;
  const PincodeRecord with_branch = LookupPincode(db_, Pincode(999501)).value();
  ASSERT_NE(MainOffice(with_branch), nullptr);
  EXPECT_EQ(MainOffice(with_branch)->name, "Beta");
  EXPECT_EQ(with_branch.district, "Subpur");
  EXPECT_EQ(with_branch.state, "Sub State");
  const PincodeRecord with_head = LookupPincode(db_, Pincode(999502)).value();
  ASSERT_NE(MainOffice(with_head), nullptr);
  EXPECT_EQ(MainOffice(with_head)->name, "Delta");
  EXPECT_EQ(with_head.district, "Headpur");
}

}  // namespace
}  // namespace pintag::db
