// Schema versions: an older file is upgraded, a newer one refused, a non-database reported.

#include <gtest/gtest.h>

#include <filesystem>

#include "db_test_util.hpp"
#include "pintag/db/registry.hpp"
#include "pintag/db/sort_plan.hpp"

namespace pintag::db {
namespace {

using test::TempDir;

TEST(Migrations, NewDatabaseUsesWalAndTheCurrentVersion) {
  Connection connection = test::OpenExisting(test::SeededTemplate());
  EXPECT_EQ(SchemaVersion(connection), kSchemaVersion);
  Statement mode = connection.prepare("PRAGMA journal_mode");
  ASSERT_TRUE(mode.step());
  EXPECT_EQ(mode.getText(0), "wal");
  EXPECT_EQ(connection.queryInt64("PRAGMA foreign_keys"), 1);
  EXPECT_EQ(connection.queryInt64("PRAGMA synchronous"), 1);  // NORMAL
}

TEST(Migrations, AnOlderFileIsUpgradedKeepingItsData) {
  TempDir dir;
  const std::string path = dir.file("v1.db");
  {
    Connection connection(path);
    MigrateTo(connection, 1);
    EXPECT_EQ(SchemaVersion(connection), 1);
    connection.execute(
        "INSERT INTO pincodes (pincode, added_at, source) VALUES (560001, 'then', 'v1');"
        "INSERT INTO tag_keys (pincode, tag_key, allocated_at) VALUES (560001, 42, 'then');");
  }
  auto opened = OpenDatabase(path);
  ASSERT_TRUE(opened.ok()) << opened.error().message;
  EXPECT_EQ(opened->upgraded_from, 1);
  EXPECT_FALSE(opened->created);
  Connection& connection = opened.value().connection;
  EXPECT_EQ(SchemaVersion(connection), kSchemaVersion);
  EXPECT_EQ(LookupPincode(connection, Pincode(560001)).value().key, TagKey(42));
  // Version 2 added plans; the upgrade gave this file the default plan.
  const auto routed = Route(connection, Pincode(560001), kDefaultPlanName);
  ASSERT_TRUE(routed.ok()) << routed.error().message;
  EXPECT_EQ(routed->bin, "56");
}

// A key, once given, stays with its pincode whatever a writer asks: UPDATE and DELETE were
// refused from version 1; INSERT OR REPLACE, whose delete fires no DELETE trigger, from version 5.
// A version-4 file gets the new trigger on open.
TEST(Migrations, TheKeyTableRefusesEveryWayOfReKeyingFromVersion4On) {
  TempDir dir;
  const std::string path = dir.file("v4.db");
  std::int64_t key_of_110001 = 0;
  {
    Connection connection(path);
    MigrateTo(connection, 4);
    connection.execute(
        "INSERT INTO pincodes (pincode, added_at, source) VALUES (110001, 'then', 'v4'), "
        "(110002, 'then', 'v4');"
        "INSERT INTO tag_keys (pincode, tag_key, allocated_at) VALUES (110001, 11684, 'then'), "
        "(110002, 20000, 'then');");
    key_of_110001 = 11684;
    // What version 4 let through: the key moved to 110002, and 110001 lost its own.
    connection.execute("BEGIN");
    connection.execute("INSERT OR REPLACE INTO tag_keys VALUES (110002, 11684, 'x')");
    EXPECT_EQ(connection.queryInt64("SELECT pincode FROM tag_keys WHERE tag_key = 11684"), 110002);
    connection.execute("ROLLBACK");
  }
  auto opened = OpenDatabase(path);
  ASSERT_TRUE(opened.ok()) << opened.error().message;
  Connection& connection = opened.value().connection;
  for (const std::string& rekey :
       {std::string("INSERT OR REPLACE INTO tag_keys VALUES (110002, 11684, 'x')"),
        std::string("REPLACE INTO tag_keys VALUES (110001, 30000, 'x')"),
        std::string("INSERT INTO tag_keys VALUES (110001, 30000, 'x') ON CONFLICT DO NOTHING"),
        std::string("INSERT OR IGNORE INTO tag_keys VALUES (110002, 11684, 'x')"),
        std::string("UPDATE tag_keys SET tag_key = 30000 WHERE pincode = 110001"),
        std::string("DELETE FROM tag_keys WHERE pincode = 110001")}) {
    try {
      connection.execute(rekey);
      ADD_FAILURE() << "not refused: " << rekey;
    } catch (const SqliteError& e) {
      EXPECT_NE(std::string(e.what()).find("append-only"), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(connection.queryInt64("SELECT tag_key FROM tag_keys WHERE pincode = 110001"),
            key_of_110001);
  EXPECT_EQ(connection.queryInt64("SELECT tag_key FROM tag_keys WHERE pincode = 110002"), 20000);
  // A new pincode still gets a new key.
  connection.execute(
      "INSERT INTO pincodes (pincode, added_at, source) VALUES (110003, 'now', 'test');"
      "INSERT INTO tag_keys (pincode, tag_key, allocated_at) VALUES (110003, 30000, 'now');");
  EXPECT_EQ(connection.queryInt64("SELECT tag_key FROM tag_keys WHERE pincode = 110003"), 30000);
}

TEST(Migrations, Version2TokensAndTheirScansSurviveTheReplicaRoleRebuild) {
  TempDir dir;
  const std::string path = dir.file("v2.db");
  {
    Connection connection(path);
    MigrateTo(connection, 2);
    connection.execute(
        "INSERT INTO api_tokens (id, role, label, salt, secret_hash, created_at) VALUES "
        "(5, 'scanner', 'old handheld', x'01', x'02', 'then');"
        "INSERT INTO scan_log (scanned_at, token_id, image_bytes, result_json) VALUES "
        "('then', 5, 100, '{}');");
  }
  auto opened = OpenDatabase(path);
  ASSERT_TRUE(opened.ok()) << opened.error().message;
  EXPECT_EQ(opened->upgraded_from, 2);
  Connection& connection = opened.value().connection;
  EXPECT_EQ(SchemaVersion(connection), kSchemaVersion);
  EXPECT_EQ(connection.queryInt64("SELECT count(*) FROM api_tokens WHERE id = 5 AND "
                                  "role = 'scanner' AND label = 'old handheld'"),
            1);
  EXPECT_EQ(connection.queryInt64("SELECT count(*) FROM scan_log WHERE token_id = 5"), 1);
  EXPECT_EQ(connection.queryInt64("SELECT count(*) FROM pragma_foreign_key_check"), 0);
  // The scan log still refers to the rebuilt table: an unknown token id is refused.
  EXPECT_THROW(connection.execute("INSERT INTO scan_log (scanned_at, token_id, image_bytes, "
                                  "result_json) VALUES ('now', 99, 1, '{}')"),
               SqliteError);
  connection.execute(
      "INSERT INTO api_tokens (role, salt, secret_hash, created_at) VALUES "
      "('replica', x'01', x'02', 'now')");
  EXPECT_THROW(connection.execute("INSERT INTO api_tokens (role, salt, secret_hash, created_at) "
                                  "VALUES ('root', x'01', x'02', 'now')"),
               SqliteError);
}

TEST(Migrations, ANewerFileIsRefusedWithAClearMessage) {
  TempDir dir;
  const std::string path = dir.file("future.db");
  {
    Connection connection(path);
    connection.execute("PRAGMA user_version = 99");
  }
  const auto opened = OpenDatabase(path);
  ASSERT_FALSE(opened.ok());
  EXPECT_EQ(opened.error().code, ErrorCode::kConflict);
  EXPECT_STREQ(ToString(opened.error().code), "conflict");
  EXPECT_NE(opened.error().message.find("schema version 99"), std::string::npos);
  EXPECT_NE(opened.error().message.find("newer than this pintag supports (" +
                                        std::to_string(kSchemaVersion) + ")"),
            std::string::npos)
      << opened.error().message;
  Connection connection(path);
  EXPECT_EQ(SchemaVersion(connection), 99);  // untouched
}

TEST(Migrations, NotADatabaseAndMissingFilesAreErrors) {
  TempDir dir;
  const std::string junk = test::WriteFile(dir.file("junk.db"), std::string(4096, 'x'));
  const auto opened = OpenDatabase(junk);
  ASSERT_FALSE(opened.ok());
  // Told from its first bytes, and named (SQLite's "file is not a database" named no file).
  EXPECT_EQ(opened.error().code, ErrorCode::kConflict);
  EXPECT_NE(opened.error().message.find(junk + " is not an SQLite database (4096 bytes"),
            std::string::npos)
      << opened.error().message;
  EXPECT_EQ(test::ReadFile(junk), std::string(4096, 'x'));
  // SQLite's header with nothing a database holds after it (a page size of 0): refused alike, and
  // not said to "not start as one".
  std::string damaged = "SQLite format 3";
  damaged += '\0';  // the header's 16 bytes end with a NUL
  damaged += std::string(600, '\xEE');
  damaged[16] = damaged[17] = '\0';
  const std::string header_only = test::WriteFile(dir.file("header.db"), damaged);
  const auto refused = OpenDatabase(header_only);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find(header_only +
                                         " is not an SQLite database (616 bytes that SQLite "
                                         "cannot read as one)"),
            std::string::npos)
      << refused.error().message;
  EXPECT_EQ(test::ReadFile(header_only), damaged);
  const auto missing = OpenDatabase(dir.file("missing.db"), {.create = false});
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.error().code, ErrorCode::kNotFound);
  EXPECT_FALSE(std::filesystem::exists(dir.file("missing.db")));
}

// A database moved away while a connection wrote to it leaves its write-ahead log at the old
// path (SQLite does not checkpoint a moved file on close). A database made there would take that
// log as its own; the open is refused, naming the log, until it is moved aside.
TEST(Migrations, AMissingFileWithALogLeftBehindIsNotRecreated) {
  TempDir dir;
  const std::string path = dir.file("registry.db");
  {
    Connection writer(path);
    writer.execute("CREATE TABLE t (x INTEGER); INSERT INTO t VALUES (1);");
    std::filesystem::rename(path, dir.file("moved.db"));
  }
  ASSERT_GT(std::filesystem::file_size(path + "-wal"), 0U);
  const auto refused = OpenDatabase(path, {.seed = false});
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, ErrorCode::kConflict);
  EXPECT_NE(refused.error().message.find(path + "-wal"), std::string::npos)
      << refused.error().message;
  EXPECT_FALSE(std::filesystem::exists(path));

  std::filesystem::rename(path + "-wal", dir.file("aside-wal"));
  std::filesystem::remove(path + "-shm");
  const auto created = OpenDatabase(path, {.seed = false});
  ASSERT_TRUE(created.ok()) << created.error().message;
}

// An SQLite file with tables and user_version 0 is another application's (each migration sets the
// version with its tables): refused, naming it, and left byte for byte as it was, journal mode
// included. An empty file is still a new database, created and seeded.
TEST(Migrations, AnotherApplicationsFileIsRefusedAndLeftAsItWas) {
  TempDir dir;
  const std::string other = dir.file("other.db");
  {
    Connection connection(other);
    connection.execute(  // in a rollback journal, as the sqlite3 shell leaves a new file
        "PRAGMA journal_mode=DELETE; CREATE TABLE x (a); CREATE TABLE y (b); "
        "INSERT INTO x VALUES (1);");
  }
  const std::string bytes = test::ReadFile(other);
  for (const OpenOptions& options :
       {OpenOptions{}, OpenOptions{.seed = false}, OpenOptions{.read_only = true}}) {
    const auto opened = OpenDatabase(other, options);
    ASSERT_FALSE(opened.ok());
    EXPECT_EQ(opened.error().code, ErrorCode::kConflict);
    EXPECT_EQ(opened.error().message,
              "database " + other +
                  " is not a PinTag database: it already holds tables (x, y) and no PinTag "
                  "schema version; give a PinTag database, or a new or empty file to create one "
                  "in");
  }
  EXPECT_EQ(test::ReadFile(other), bytes);
  EXPECT_FALSE(std::filesystem::exists(other + "-wal"));

  const std::string empty = test::WriteFile(dir.file("empty.db"), "");
  auto created = OpenDatabase(empty);
  ASSERT_TRUE(created.ok()) << created.error().message;
  EXPECT_TRUE(created->created);
  EXPECT_EQ(CountRegistry(created.value().connection).value().pincodes_active, 19159);
}

// Another program's file may set user_version too (Firefox's places.sqlite is at 74): a version
// without PinTag's tables is refused as foreign, not read as a newer or older PinTag schema, and
// the file is left byte for byte, not even switched to WAL.
TEST(Migrations, AnotherApplicationsVersionedFileIsRefusedAndLeftAsItWas) {
  TempDir dir;
  for (const int version : {2, kSchemaVersion, 74}) {
    const std::string other = dir.file("other" + std::to_string(version) + ".db");
    {
      Connection connection(other);
      connection.execute(
          "PRAGMA journal_mode=DELETE; CREATE TABLE moz_places (a); PRAGMA "
          "user_version=" +
          std::to_string(version));
    }
    const std::string bytes = test::ReadFile(other);
    for (const OpenOptions& options : {OpenOptions{}, OpenOptions{.read_only = true}}) {
      const auto opened = OpenDatabase(other, options);
      ASSERT_FALSE(opened.ok()) << version;
      EXPECT_EQ(opened.error().code, ErrorCode::kConflict);
      EXPECT_EQ(opened.error().message,
                "database " + other +
                    " is not a PinTag database: it already holds tables (moz_places) and schema "
                    "version " +
                    std::to_string(version) +
                    " but not PinTag's tables; give a PinTag database, or a new or empty file to "
                    "create one in");
    }
    EXPECT_EQ(test::ReadFile(other), bytes) << version;
    EXPECT_FALSE(std::filesystem::exists(other + "-wal"));
  }
}

// A PinTag file newer than this build is refused as newer, and not switched to WAL by the look.
TEST(Migrations, ANewerPinTagFileIsRefusedAndLeftAsItWas) {
  TempDir dir;
  const std::string path = test::CopyOfSeeded(dir);
  {
    Connection connection(path);
    connection.execute("PRAGMA journal_mode=DELETE; PRAGMA user_version=" +
                       std::to_string(kSchemaVersion + 1));
  }
  const std::string bytes = test::ReadFile(path);
  const auto opened = OpenDatabase(path);
  ASSERT_FALSE(opened.ok());
  EXPECT_NE(opened.error().message.find("newer than this pintag supports"), std::string::npos)
      << opened.error().message;
  EXPECT_EQ(test::ReadFile(path), bytes);
}

TEST(Migrations, ReadOnlyOpenWorksOnCurrentFiles) {
  TempDir dir;
  const std::string path = test::CopyOfSeeded(dir);
  auto opened = OpenDatabase(path, {.read_only = true});
  ASSERT_TRUE(opened.ok()) << opened.error().message;
  EXPECT_TRUE(LookupPincode(opened.value().connection, Pincode(110001)).ok());
  EXPECT_FALSE(RetirePincode(opened.value().connection, Pincode(110001)).ok());
}

}  // namespace
}  // namespace pintag::db
