// `pintag keys lookup` and `pintag render` read a key with the parser the {key} route uses: the
// same keys pass, the same text is refused with the same words.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "serve_fixture.hpp"

namespace pintag::serve_test {
namespace {

// A copy of the seeded registry in `dir`, for a command to read; its path.
std::string SeededCopy(const TempDir& dir) {
  std::string db = dir.file("copy.db");
  std::filesystem::copy_file(SeededTemplate(), db);
  return db;
}

TEST(CliKeys, LookupByKeyFindsItsPincode) {
  const TempDir dir;
  const std::string db = SeededCopy(dir);
  const CommandResult found = RunPintag("keys lookup --key 11684 --db " + db);
  EXPECT_EQ(found.status, 0) << found.out;
  EXPECT_NE(found.out.find("pincode  110001"), std::string::npos) << found.out;
}

// A replica's snapshot read by the commands that only read stays a snapshot, byte for byte:
// opened to be written, it was switched to WAL mode, and the replica then refused it.
TEST(CliKeys, CommandsThatReadLeaveASnapshotAsItIs) {
  const TempDir dir;
  const std::string db = SeededCopy(dir);
  const std::string snapshot = dir.file("snapshot.db");
  ASSERT_EQ(RunPintag("snapshot --db " + db + " --out " + snapshot).status, 0);
  const std::string before = ReadFile(snapshot);
  for (const std::string& command :
       {"keys lookup 110001 --db " + snapshot, "keys lookup --key 11684 --db " + snapshot,
        "keys export --db " + snapshot + " > /dev/null", "token list --db " + snapshot}) {
    const CommandResult read = RunPintag(command);
    EXPECT_EQ(read.status, 0) << command << ": " << read.out;
  }
  EXPECT_TRUE(ReadFile(snapshot) == before) << "the snapshot changed";
  EXPECT_FALSE(std::filesystem::exists(snapshot + "-wal"));
  const CommandResult verified = RunPintag("snapshot --verify " + snapshot);
  EXPECT_EQ(verified.status, 0) << verified.out;
  // A file that is no database is named in the error.
  const std::string junk = dir.file("junk.db");
  WriteFile(junk, std::string(4096, 'j'));
  const CommandResult refused = RunPintag("keys lookup 110001 --db " + junk);
  EXPECT_EQ(refused.status, 1) << refused.out;
  EXPECT_NE(refused.out.find("database " + junk + " is not an SQLite database"), std::string::npos)
      << refused.out;
}

TEST(CliKeys, LookupSaysWhatIsMissingOrTooMuch) {
  const TempDir dir;
  const std::string db = SeededCopy(dir);
  const CommandResult neither = RunPintag("keys lookup --db " + db);
  EXPECT_EQ(neither.status, 2);
  EXPECT_NE(neither.out.find("give a pincode or --key KEY"), std::string::npos) << neither.out;
  const CommandResult both = RunPintag("keys lookup 110001 --key 11684 --db " + db);
  EXPECT_NE(both.status, 0);
  EXPECT_NE(both.out.find("not both"), std::string::npos) << both.out;
}

TEST(CliKeys, KeysOutsideTheRangeAreRefusedAsTheApiRefusesThem) {
  const TempDir dir;
  for (const char* key : {"32768", "-1", "abc", "1e3", "0x10"}) {
    for (const std::string& command :
         {"keys lookup --db " + dir.file("never.db") + " --key " + key,
          "render -o " + dir.file("tag.png") + " --size-px 128 --key " + key}) {
      const CommandResult refused = RunPintag(command);
      EXPECT_EQ(refused.status, 2) << command << ": " << refused.out;
      EXPECT_NE(refused.out.find("a key is an integer from 0 to 32767"), std::string::npos)
          << command << ": " << refused.out;
    }
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("never.db")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("tag.png")));
}

// CLI11 read integers with strtoll's base 0: `--key 010` was key 8, a tag for another pincode.
// Leading zeros are decimal, as the {key} route reads them; hex is refused on every integer.
TEST(CliKeys, LeadingZerosAreDecimalOnEveryIntegerOption) {
  const TempDir dir;
  const std::string db = SeededCopy(dir);
  const CommandResult plain = RunPintag("keys lookup --key 10 --db " + db);
  ASSERT_EQ(plain.status, 0) << plain.out;
  for (const char* key : {"010", "0010", "000000010"}) {
    const CommandResult padded = RunPintag(std::string("keys lookup --key ") + key + " --db " + db);
    EXPECT_EQ(padded.out, plain.out) << key;
  }
  // The tag drawn for --key 010 is read back by the detector as key 10.
  const std::string png = dir.file("tag.png");
  ASSERT_EQ(RunPintag("render --key 010 --size-px 0256 -o " + png).status, 0);
  const CommandResult read = RunPintag("detect --json " + png);
  ASSERT_EQ(read.status, 0) << read.out;
  const nlohmann::json detections = nlohmann::json::parse(read.out)["detections"];
  ASSERT_EQ(detections.size(), 1U) << read.out;
  EXPECT_EQ(detections[0]["key"], 10) << read.out;
  // Past 18 digits CLI11 took strtoll's clamped answer: refused instead.
  const CommandResult huge = RunPintag("token revoke 99999999999999999999 --db " + db);
  EXPECT_EQ(huge.status, 2) << huge.out;
  EXPECT_NE(huge.out.find("is too large: '99999999999999999999'"), std::string::npos) << huge.out;
  const CommandResult hex = RunPintag("render --key 5 --size-px 0x100 -o " + png);
  EXPECT_EQ(hex.status, 2) << hex.out;
  EXPECT_NE(hex.out.find("must be a whole number in decimal digits, got '0x100'"),
            std::string::npos)
      << hex.out;
}

TEST(CliKeys, RenderSaysWhyASizeInMillimetresIsRefusedInTheUsersNumbers) {
  const TempDir dir;
  // 2 mm at 300 dpi is 24 px, under the smallest square a tag may be drawn at.
  const CommandResult small =
      RunPintag("render --key 5 --size-mm 2 --dpi 300 -o " + dir.file("tag.png"));
  EXPECT_EQ(small.status, 2) << small.out;
  EXPECT_NE(small.out.find("--size-mm 2 at 300 dpi gives a 24 px square"), std::string::npos)
      << small.out;
  const CommandResult fraction =
      RunPintag("render --key 5 --size-mm 2.5 --dpi 150 -o " + dir.file("tag.png"));
  EXPECT_NE(fraction.out.find("--size-mm 2.5 at 150 dpi"), std::string::npos) << fraction.out;
  EXPECT_FALSE(std::filesystem::exists(dir.file("tag.png")));
  // An SVG has no resolution: a --dpi given for one was dropped without a word.
  const CommandResult svg =
      RunPintag("render --key 5 --size-px 256 --dpi 600 -o " + dir.file("tag.svg"));
  EXPECT_EQ(svg.status, 2) << svg.out;
  EXPECT_NE(svg.out.find("--dpi is for PNGs"), std::string::npos) << svg.out;
  EXPECT_FALSE(std::filesystem::exists(dir.file("tag.svg")));
  EXPECT_EQ(RunPintag("render --key 5 --size-mm 20 -o " + dir.file("tag.svg")).status, 0);
}

TEST(CliKeys, NumbersThatAreNotFiniteAreRefusedLikeAnyOutOfRange) {
  // CLI11's ranges compare with < and >, which NaN passes: a render of "nan mm" once succeeded.
  const TempDir dir;
  for (const std::string& command :
       {"render --key 5 --size-mm nan -o " + dir.file("tag.svg"),
        "render --key 5 --size-px 200 --dpi inf -o " + dir.file("tag.png"),
        "serve --max-body-mb nan --port 0 --db " + dir.file("never.db")}) {
    const CommandResult refused = RunPintag(command);
    EXPECT_EQ(refused.status, 2) << command << ": " << refused.out;
    EXPECT_NE(refused.out.find("must be a finite number"), std::string::npos)
        << command << ": " << refused.out;
  }
  // Text that is not a decimal number is refused as such, not as a number that is not finite.
  const CommandResult hex =
      RunPintag("render --key 5 --size-px 200 --dpi 0x12C -o " + dir.file("tag.png"));
  EXPECT_EQ(hex.status, 2) << hex.out;
  EXPECT_NE(hex.out.find("must be a decimal number (such as 300 or 0.5), got '0x12C'"),
            std::string::npos)
      << hex.out;
  EXPECT_FALSE(std::filesystem::exists(dir.file("tag.svg")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("tag.png")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("never.db")));
}

TEST(CliKeys, ExitStatusTellsAWrongCommandLineFromAFailedJob) {
  // 2: the command line is wrong, whether CLI11 or the command found it; 1: the job failed.
  const TempDir dir;
  EXPECT_EQ(RunPintag("keys lookup 110001 --no-such-option").status, 2);
  EXPECT_EQ(RunPintag("serve --port not-a-port --db " + dir.file("never.db")).status, 2);
  EXPECT_EQ(RunPintag("no-such-command").status, 2);
  EXPECT_EQ(RunPintag("keys --help").status, 0);
  EXPECT_EQ(RunPintag("detect " + dir.file("missing.jpg")).status, 1);
  EXPECT_FALSE(std::filesystem::exists(dir.file("never.db")));
}

TEST(CliKeys, AMistypedSubcommandIsNamedAndTheVersionIsShown) {
  // CLI11 said "A subcommand is required" to a subcommand mistyped.
  const CommandResult mistyped = RunPintag("serv --db x.db");
  EXPECT_EQ(mistyped.status, 2) << mistyped.out;
  EXPECT_NE(mistyped.out.find("'serv' is not a subcommand; the subcommands are detect, import, "
                              "keys, render, scans, serve, snapshot, token"),
            std::string::npos)
      << mistyped.out;
  const CommandResult version = RunPintag("--version");
  EXPECT_EQ(version.status, 0) << version.out;
  EXPECT_EQ(version.out.rfind("pintag ", 0), 0U) << version.out;
  EXPECT_NE(version.out.find("(registry schema "), std::string::npos) << version.out;
}

TEST(CliKeys, AMistypedRequiredOptionIsNamedNotTakenForAMissingOne) {
  // CLI11 checks required options first: "--kye 5" was answered "--key is required".
  const TempDir dir;
  const CommandResult render = RunPintag("render --kye 5 --size-px 100 -o " + dir.file("t.png"));
  EXPECT_EQ(render.status, 2) << render.out;
  EXPECT_NE(render.out.find("unknown option --kye (--key is required)"), std::string::npos)
      << render.out;
  const CommandResult token = RunPintag("token create --rol admin --db " + dir.file("t.db"));
  EXPECT_EQ(token.status, 2) << token.out;
  EXPECT_NE(token.out.find("unknown option --rol"), std::string::npos) << token.out;
  EXPECT_FALSE(std::filesystem::exists(dir.file("t.db")));
  // Only missing: said as before.
  const CommandResult missing = RunPintag("render --size-px 100 -o " + dir.file("t.png"));
  EXPECT_EQ(missing.status, 2) << missing.out;
  EXPECT_EQ(missing.out.rfind("--key is required", 0), 0U) << missing.out;
}

}  // namespace
}  // namespace pintag::serve_test
