// A `pintag` command given a wrong argument or a bad input file says so before it opens its
// database: no new database is created and seeded (35 MB) only to be left behind.

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "pintag/db/database.hpp"
#include "pintag/db/sqlite.hpp"
#include "serve_fixture.hpp"

namespace pintag::serve_test {
namespace {

TEST(CliNewDb, AMalformedPincodeIsRefusedBeforeTheDatabaseIsCreated) {
  const TempDir dir;
  const std::string db = dir.file("new.db");
  const CommandResult run = RunPintag("keys lookup abc --db " + db);
  EXPECT_EQ(run.status, 2) << run.out;
  EXPECT_NE(run.out.find("'abc'"), std::string::npos) << run.out;
  EXPECT_EQ(run.out.find("created"), std::string::npos) << run.out;
  EXPECT_FALSE(std::filesystem::exists(db));
}

TEST(CliNewDb, ABadTokenLabelIsAUsageErrorBeforeTheDatabaseIsCreated) {
  const TempDir dir;
  const std::string db = dir.file("new.db");
  const CommandResult tab =
      RunPintag("token create --role admin --label \"$(printf 'a\\tb')\" --db " + db);
  EXPECT_EQ(tab.status, 2) << tab.out;
  EXPECT_NE(tab.out.find("--label contains control character 9"), std::string::npos) << tab.out;
  const CommandResult long_label =
      RunPintag("token create --role admin --label " + std::string(201, 'x') + " --db " + db);
  EXPECT_EQ(long_label.status, 2) << long_label.out;
  // A label of spaces (a no-break one among them) labels nothing in a list.
  const CommandResult blank =
      RunPintag("token create --role admin --label \"$(printf '  \\302\\240 ')\" --db " + db);
  EXPECT_EQ(blank.status, 2) << blank.out;
  EXPECT_NE(blank.out.find("--label is blank"), std::string::npos) << blank.out;
  EXPECT_FALSE(std::filesystem::exists(db));

  // A good label still makes a token (and, the file being missing, the database).
  const CommandResult made = RunPintag("token create --role admin --label 'desk 2' --db " + db);
  EXPECT_EQ(made.status, 0) << made.out;
  EXPECT_NE(made.out.find("pt_"), std::string::npos) << made.out;
  EXPECT_TRUE(std::filesystem::exists(db));
}

// A primary's --snapshot in a directory that is not there was refused only once its database
// had been created and seeded.
TEST(CliNewDb, ASnapshotDirectoryThatIsNotThereIsRefusedBeforeTheDatabaseIsCreated) {
  const TempDir dir;
  const std::string db = dir.file("new.db");
  const std::string snapshot = dir.file("no-such-dir") + "/snap.db";
  // Under a timeout: a server that started would serve on.
  const CommandResult run = RunShell("timeout 60 " + PintagExe() + " serve --port 0 --db " + db +
                                     " --snapshot " + snapshot + " 2>&1");
  EXPECT_EQ(run.status, 2) << run.out;
  EXPECT_NE(run.out.find("--snapshot " + snapshot + ": its directory"), std::string::npos)
      << run.out;
  EXPECT_FALSE(std::filesystem::exists(db));
  // Nor a pipe at the path, which no snapshot can ever be: the server started, and logged a
  // failed publication every second. (A directory there is a publication that fails until it is
  // removed: ReplicaSetTest.APrimaryStartsWhenItsFirstSnapshotCannotBeWrittenAndPublishesLater.)
  ASSERT_EQ(::mkfifo(dir.file("a-pipe").c_str(), 0600), 0);
  const CommandResult piped = RunShell("timeout 60 " + PintagExe() + " serve --port 0 --db " + db +
                                       " --snapshot " + dir.file("a-pipe") + " 2>&1");
  EXPECT_EQ(piped.status, 2) << piped.out;
  EXPECT_NE(piped.out.find("--snapshot " + dir.file("a-pipe") + " is a pipe"), std::string::npos)
      << piped.out;
  EXPECT_FALSE(std::filesystem::exists(db));
  // A replica given one (a PINTAG_SNAPSHOT shared with the primary) is told it has none to give.
  const CommandResult replica = RunShell("timeout 60 " + PintagExe() + " serve --port 0 --db " +
                                         db + " --read-only --snapshot " + snapshot + " 2>&1");
  EXPECT_EQ(replica.status, 2) << replica.out;
  EXPECT_NE(replica.out.find("a --read-only replica has none"), std::string::npos) << replica.out;
  // A follower whose --scan-log is its --db, not there yet: it was made a scan log, and every
  // snapshot was then refused while the follower waited for its first one.
  const CommandResult same = RunShell(
      "PINTAG_FOLLOW_TOKEN=pt_1_" + std::string(43, 'A') + " timeout 60 " + PintagExe() +
      " serve --port 0 --follow http://127.0.0.1:9 --db " + db + " --scan-log " + db + " 2>&1");
  EXPECT_EQ(same.status, 2) << same.out;
  EXPECT_NE(same.out.find("is the replica's --db"), std::string::npos) << same.out;
  EXPECT_FALSE(std::filesystem::exists(db));
}

// Listing or revoking the tokens of a database that is not there is a mistyped path: it was
// created and seeded, then said "no token -3".
TEST(CliNewDb, TokenListAndRevokeNeedAnExistingDatabase) {
  const TempDir dir;
  const std::string db = dir.file("new.db");
  for (const char* id : {"-3", "0", "00", "x"}) {
    const CommandResult run = RunPintag(std::string("token revoke --db ") + db + " -- " + id);
    EXPECT_EQ(run.status, 2) << id << ": " << run.out;
    EXPECT_NE(run.out.find(std::string("got '")), std::string::npos) << run.out;
  }
  for (const std::string& command : {"token revoke 3 --db " + db, "token list --db " + db}) {
    const CommandResult run = RunPintag(command);
    EXPECT_EQ(run.status, 1) << command << ": " << run.out;
    EXPECT_NE(run.out.find("no database at " + db), std::string::npos) << run.out;
  }
  EXPECT_FALSE(std::filesystem::exists(db));
  // An empty file is no database to list or revoke from: it was seeded (35 MB) to list nothing.
  const std::string empty = WriteFile(dir.file("empty.db"), "");
  for (const std::string& command : {"token revoke 1 --db " + empty, "token list --db " + empty}) {
    const CommandResult run = RunPintag(command);
    EXPECT_EQ(run.status, 1) << command << ": " << run.out;
    EXPECT_NE(run.out.find(empty + " is empty: not a PinTag database"), std::string::npos)
        << run.out;
  }
  EXPECT_EQ(std::filesystem::file_size(empty), 0U);
}

// A file that holds something other than an SQLite database is refused by every command and left
// as it was. SQLite took a file of one byte for an empty database: it was seeded over.
TEST(CliNewDb, AFileThatIsNoSqliteDatabaseIsRefusedAndLeftAsItWas) {
  const TempDir dir;
  for (const std::string& bytes :
       {std::string("x"), std::string("notes\n"), std::string(600, 'z')}) {
    const std::string db = WriteFile(dir.file("f.db"), bytes);
    for (const std::string& command :
         {"keys lookup 110001 --db " + db, "token create --role admin --db " + db}) {
      const CommandResult run = RunPintag(command);
      EXPECT_EQ(run.status, 1) << bytes.size() << " bytes, " << command << ": " << run.out;
      EXPECT_NE(run.out.find("database " + db + " is not an SQLite database (" +
                             std::to_string(bytes.size())),
                std::string::npos)
          << run.out;
      EXPECT_EQ(ReadFile(db), bytes);
      EXPECT_FALSE(std::filesystem::exists(db + "-wal"));
    }
  }
  // What is at --db, or is not, said in these words: SQLite said "unable to open database file"
  // or "disk I/O error", and the command named the file twice.
  std::filesystem::create_directory(dir.file("a-directory"));
  for (const auto& [db, says] : std::vector<std::pair<std::string, std::string>>{
           {dir.file("a-directory"), " is a directory, not a database file"},
           {"/dev/null", " is a device, not a database file"},
           {dir.file("no-such-dir") + "/x.db", " cannot be made: its directory "}}) {
    const CommandResult run = RunPintag("keys lookup 110001 --db " + db);
    EXPECT_EQ(run.status, 1) << db << ": " << run.out;
    std::string expected = "pintag: database ";
    expected += db;
    expected += says;
    EXPECT_EQ(run.out.rfind(expected, 0), 0U) << run.out;
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("no-such-dir")));
}

// An empty file at --db (`touch`, a mount's placeholder) is seeded as a new database and said
// so, not said to be created; a snapshot check of one says it holds no registry.
TEST(CliNewDb, AnEmptyFileIsSeededAndSaidToBeAndIsNoSnapshot) {
  const TempDir dir;
  const std::string empty = WriteFile(dir.file("empty.db"), "");
  const CommandResult verified = RunPintag("snapshot --verify " + empty);
  EXPECT_EQ(verified.status, 1) << verified.out;
  EXPECT_NE(verified.out.find("holds no PinTag registry (it is empty"), std::string::npos)
      << verified.out;
  EXPECT_EQ(verified.out.find("schema version 0"), std::string::npos) << verified.out;

  const CommandResult made = RunPintag("token create --role admin --db " + empty);
  EXPECT_EQ(made.status, 0) << made.out;
  EXPECT_NE(made.out.find("seeded the empty file " + empty + " from "), std::string::npos)
      << made.out;
  EXPECT_EQ(made.out.find("created " + empty), std::string::npos) << made.out;

  // Revoking it twice: the second says it was already revoked, at the first one's time.
  const CommandResult first = RunPintag("token revoke 1 --db " + empty);
  EXPECT_EQ(first.status, 0) << first.out;
  const std::size_t at = first.out.find("revoked at ");
  ASSERT_NE(at, std::string::npos) << first.out;
  const std::string when = first.out.substr(at + 11, first.out.find('\n', at) - at - 11);
  const CommandResult second = RunPintag("token revoke 1 --db " + empty);
  EXPECT_EQ(second.status, 0) << second.out;
  EXPECT_NE(second.out.find("token 1 was already revoked at " + when), std::string::npos)
      << second.out;
}

// `pintag import -` read a file named "-" ("cannot read -: No such file or directory"), where
// `pintag detect -` reads standard input: it reads standard input too, and names it so.
TEST(CliNewDb, ImportReadsStandardInputForADash) {
  const TempDir dir;
  const std::string csv = WriteFile(
      dir.file("one.csv"),
      "circlename,regionname,divisionname,officename,pincode,officetype,delivery,district,"
      "statename,latitude,longitude\n"
      "Delhi,Delhi,New Delhi,Somewhere,999872,BO,Delivery,Central Delhi,Delhi,NA,NA\n");
  const std::string db = dir.file("stdin.db");
  const CommandResult imported =
      RunShell(PintagExe() + " import - --db " + db + " < " + csv + " 2>&1");
  EXPECT_EQ(imported.status, 0) << imported.out;
  EXPECT_NE(imported.out.find("imported standard input ("), std::string::npos) << imported.out;
  EXPECT_EQ(RunPintag("keys lookup 999872 --db " + db).status, 0);
  const std::string junk = WriteFile(dir.file("junk.csv"), "not,a,directory\n1,2,3\n");
  const CommandResult refused =
      RunShell(PintagExe() + " import - --db " + dir.file("other.db") + " < " + junk + " 2>&1");
  EXPECT_EQ(refused.status, 1) << refused.out;
  EXPECT_NE(refused.out.find("pintag: standard input: line 1: not an All India Pincode Directory"),
            std::string::npos)
      << refused.out;
  EXPECT_FALSE(std::filesystem::exists(dir.file("other.db")));
}

TEST(CliNewDb, ABadImportFileLeavesNoNewDatabase) {
  const TempDir dir;
  const std::string header =
      "circlename,regionname,divisionname,officename,pincode,officetype,delivery,district,"
      "statename,latitude,longitude\n";
  const std::string bad_row = "Delhi,Delhi,New Delhi,Nowhere,12345,BO,Delivery,X,Y,NA,NA\n";
  const std::string good_row = "Delhi,Delhi,New Delhi,Somewhere,110001,BO,Delivery,X,Y,NA,NA\n";
  std::string lacking_district = header;
  lacking_district.erase(lacking_district.find("district,"), 9);
  // The same good file as Excel's "Unicode Text" saves it (UTF-16 LE with a byte order mark),
  // and with semicolons or tabs between the fields.
  std::string utf16 = "\xFF\xFE";
  for (const char c : header + good_row) utf16.append({c, '\0'});
  std::string semicolons = header + good_row;
  std::replace(semicolons.begin(), semicolons.end(), ',', ';');
  std::string tabs = header + good_row;
  std::replace(tabs.begin(), tabs.end(), ',', '\t');
  struct Case {
    const char* name;
    std::string content;
    const char* options;
    const char* says;
  };
  const Case cases[] = {
      {"empty.csv", "", "", "the file is empty"},
      {"header.csv", "pincode,name\n110001,x\n", "", "not an All India Pincode Directory header"},
      {"quote.csv", header + "\"Delhi,Delhi\n", "", "never closed"},
      {"all_bad.csv", header + bad_row + bad_row, "", "none of its 2 rows could be imported"},
      {"strict.csv", header + bad_row, "--strict", "--strict: 1 bad row, nothing imported"},
      {"header_only.csv", header + "\n", "",
       "header_only.csv: the file has a header and no data rows; nothing to import"},
      {"unknown_places.csv",
       header + "Delhi,Delhi,New Delhi,Nowhere,110001,PO,Delivery,NA,NA,NA,NA\n", "",
       "unknown_places.csv:2: district is 'NA', which means unknown; it is required"},
      {"pincode_twice.csv", "pincode," + header + "110001," + good_row, "",
       "the header has the column pincode 2 times (fields 1 and 6)"},
      {"lacking_district.csv", lacking_district + good_row, "",
       "missing the newer layout's district ("},
      {"utf16.csv", utf16, "", "the file is UTF-16 text"},
      {"utf16_no_bom.csv", utf16.substr(2), "", "the file is not text (it holds NUL bytes"},
      {"semicolons.csv", semicolons, "", "line 1: the fields are separated by semicolons"},
      {"tabs.csv", tabs, "", "line 1: the fields are separated by tabs"},
  };
  for (const Case& c : cases) {
    const std::string file = WriteFile(dir.path() / c.name, c.content);
    const std::string db = dir.file(std::string(c.name) + ".db");
    std::string command = "import " + file;
    command.append(" --db ").append(db).append(" ").append(c.options);
    const CommandResult run = RunPintag(command);
    EXPECT_EQ(run.status, 1) << c.name << ": " << run.out;
    EXPECT_NE(run.out.find(c.says), std::string::npos) << c.name << ": " << run.out;
    EXPECT_EQ(run.out.find("created"), std::string::npos) << c.name << ": " << run.out;
    EXPECT_FALSE(std::filesystem::exists(db)) << c.name;
  }
  // The good file compressed, as a download may come.
  const std::string good = WriteFile(dir.path() / "good.csv", header + good_row);
  ASSERT_EQ(RunShell("gzip -k " + good).status, 0);
  const CommandResult gzipped = RunPintag("import " + good + ".gz --db " + dir.file("gz.db"));
  EXPECT_EQ(gzipped.status, 1) << gzipped.out;
  EXPECT_NE(gzipped.out.find("the file is compressed (gzip)"), std::string::npos) << gzipped.out;
  EXPECT_FALSE(std::filesystem::exists(dir.file("gz.db")));
  // A file with no end is refused at the size limit, not read until memory runs out.
  const std::string db = dir.file("zero.db");
  const CommandResult endless =
      RunShell("ulimit -v 2000000; " + PintagExe() + " import /dev/zero --db " + db + " 2>&1");
  EXPECT_EQ(endless.status, 1) << endless.out;
  EXPECT_NE(endless.out.find("/dev/zero is larger than 256 MiB"), std::string::npos) << endless.out;
  EXPECT_FALSE(std::filesystem::exists(db));
}

// An SQLite file of another application's (user_version 0, tables of its own) is not seeded in
// place: every command that opens a --db refuses it, naming it, and leaves it as it was, where
// `pintag import basic.csv --db other.db` wrote PinTag's schema and 154,874 offices into it.
TEST(CliNewDb, AnotherApplicationsDatabaseIsRefusedAndLeftAsItWas) {
  const TempDir dir;
  const std::string other = dir.file("other.db");
  {
    db::Connection connection(other);
    // In a rollback journal, as `sqlite3 other.db "create table x(a)"` leaves it.
    connection.execute("PRAGMA journal_mode=DELETE; CREATE TABLE x (a); INSERT INTO x VALUES (1);");
  }
  const std::string bytes = ReadFile(other);
  const std::string csv = WriteFile(
      dir.path() / "basic.csv",
      "circlename,regionname,divisionname,officename,pincode,officetype,delivery,district,"
      "statename,latitude,longitude\n"
      "Delhi,Delhi,New Delhi,Somewhere,110001,BO,Delivery,X,Y,NA,NA\n");
  const std::string says = other + " is not a PinTag database: it already holds tables (x)";
  const std::vector<std::string> commands = {
      "import " + csv + " --db " + other, "token create --role admin --db " + other,
      "keys lookup 110001 --db " + other,
      "snapshot --db " + other + " --out " + dir.file("snapshot.db")};
  for (const std::string& command : commands) {
    const CommandResult run = RunPintag(command);
    EXPECT_EQ(run.status, 1) << command << ": " << run.out;
    EXPECT_NE(run.out.find(says), std::string::npos) << command << ": " << run.out;
    EXPECT_EQ(run.out.find("created"), std::string::npos) << command << ": " << run.out;
  }
  const std::string serve_err = dir.file("serve.err");
  ServerProcess server({"--db", other}, serve_err, 60);
  EXPECT_FALSE(server.ok()) << "served another application's database";
  EXPECT_EQ(server.stop(), 1) << ReadFile(serve_err);
  EXPECT_NE(ReadFile(serve_err).find(says), std::string::npos) << ReadFile(serve_err);
  EXPECT_EQ(ReadFile(other), bytes);
  EXPECT_FALSE(std::filesystem::exists(other + "-wal"));
  EXPECT_FALSE(std::filesystem::exists(dir.file("snapshot.db")));

  // One whose user_version happens to be PinTag's schema version: the commands that only read
  // took it for a registry and failed on SQLite's "no such table: pincodes".
  const std::string numbered = dir.file("numbered.db");
  {
    db::Connection connection(numbered);
    connection.execute("PRAGMA journal_mode=DELETE; CREATE TABLE x (a); PRAGMA user_version=" +
                       std::to_string(db::kSchemaVersion));
  }
  for (const std::string& command :
       {"keys lookup 110001 --db " + numbered, "keys export --db " + numbered,
        "token list --db " + numbered}) {
    const CommandResult run = RunPintag(command);
    EXPECT_EQ(run.status, 1) << command << ": " << run.out;
    EXPECT_NE(run.out.find(numbered + " is not a PinTag database: it already holds tables (x)"),
              std::string::npos)
        << command << ": " << run.out;
  }
}

}  // namespace
}  // namespace pintag::serve_test
