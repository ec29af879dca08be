// Running `pintag serve`: first start, readiness, metrics, the OpenAPI document against the live
// routes, static files, graceful shutdown.

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <fstream>
#include <functional>
#include <regex>
#include <set>
#include <thread>

#include "pintag/db/database.hpp"
#include "pintag/db/registry.hpp"
#include "pintag/db/scan_log.hpp"
#include "pintag/db/tokens.hpp"
#include "pintag/test/loopback_socket.hpp"
#include "serve_fixture.hpp"

namespace pintag::serve_test {
namespace {

using nlohmann::json;

std::string Upper(std::string text) {
  for (char& c : text) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return text;
}

std::set<std::string> Secrets(const std::string& text) {
  std::set<std::string> found;
  const std::regex secret(R"(pt_\d+_[A-Za-z0-9_-]{43})");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), secret);
       it != std::sregex_iterator(); ++it) {
    found.insert(it->str());
  }
  return found;
}

TEST(ServeFirstStart, CreatesSeedsAndPrintsOneAdminTokenOnStdoutOnly) {
  TempDir dir;
  const std::string db_path = dir.file("new.db");
  std::string secret;
  {
    ServerProcess server({"--db", db_path}, dir.file("stderr.log"));
    ASSERT_TRUE(server.ok()) << server.out() << ReadFile(dir.file("stderr.log"));
    const std::set<std::string> secrets = Secrets(server.out());
    ASSERT_EQ(secrets.size(), 1U) << server.out();
    secret = *secrets.begin();
    EXPECT_NE(server.out().find("http://127.0.0.1:" + std::to_string(server.port())),
              std::string::npos);

    httplib::Client client("127.0.0.1", server.port());
    auto r = client.Get("/api/v1/tokens", {{"Authorization", "Bearer " + secret}});
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 200) << r->body;
    const json tokens = json::parse(r->body)["tokens"];
    ASSERT_EQ(tokens.size(), 1U);
    EXPECT_EQ(tokens[0]["role"], "admin");
    r = client.Get("/api/v1/pincodes/110001");  // seeded
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200);
    EXPECT_EQ(server.stop(SIGTERM), 0);
  }
  // Nowhere else: not on stderr, not in the database files (only a salted hash is kept).
  const std::string stderr_text = ReadFile(dir.file("stderr.log"));
  EXPECT_NE(stderr_text.find("created"), std::string::npos) << stderr_text;
  EXPECT_EQ(stderr_text.find(secret), std::string::npos);
  EXPECT_TRUE(Secrets(stderr_text).empty());
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    EXPECT_EQ(ReadFile(entry.path().string()).find(secret.substr(5)), std::string::npos)
        << entry.path();
  }
  // A second start finds the token table non-empty and prints no token.
  ServerProcess again({"--db", db_path}, dir.file("stderr.log"));
  ASSERT_TRUE(again.ok());
  EXPECT_TRUE(Secrets(again.out()).empty()) << again.out();
  EXPECT_NE(again.out().find("pintag token create"), std::string::npos);
}

TEST(ServeFirstStart, WritesTheFirstAdminTokenToTheFileAskedForAndNotToStdout) {
  // A container's stdout is kept in its log: with --admin-token-out the secret goes to a file.
  const TempDir dir;
  const std::string db_path = dir.file("new.db");
  const std::string token_file = dir.file("first-admin.token");
  {
    ServerProcess server({"--db", db_path, "--admin-token-out", token_file},
                         dir.file("stderr.log"));
    ASSERT_TRUE(server.ok()) << server.out() << ReadFile(dir.file("stderr.log"));
    EXPECT_TRUE(Secrets(server.out()).empty()) << server.out();
    EXPECT_NE(server.out().find("secret is in " + token_file), std::string::npos) << server.out();
    const std::set<std::string> in_file = Secrets(ReadFile(token_file));
    ASSERT_EQ(in_file.size(), 1U) << ReadFile(token_file);
    EXPECT_EQ(std::filesystem::status(token_file).permissions() & std::filesystem::perms::all,
              std::filesystem::perms::owner_read | std::filesystem::perms::owner_write);
    httplib::Client client("127.0.0.1", server.port());
    auto r = client.Get("/api/v1/tokens", {{"Authorization", "Bearer " + *in_file.begin()}});
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 200) << r->body;
    EXPECT_EQ(json::parse(r->body)["tokens"][0]["role"], "admin");
    EXPECT_EQ(server.stop(SIGTERM), 0);
  }
  EXPECT_TRUE(Secrets(ReadFile(dir.file("stderr.log"))).empty());
  // A later start makes no token, and writes no file.
  std::filesystem::remove(token_file);
  {
    ServerProcess again({"--db", db_path, "--admin-token-out", token_file}, dir.file("stderr.log"));
    ASSERT_TRUE(again.ok());
    EXPECT_TRUE(Secrets(again.out()).empty()) << again.out();
  }
  EXPECT_FALSE(std::filesystem::exists(token_file));
  // A file in a directory that is not there: refused before the database is made.
  const CommandResult refused =
      RunPintag("serve --port 0 --bind 127.0.0.1 --db " + dir.file("other.db") +
                " --admin-token-out " + dir.file("missing/first-admin.token"));
  EXPECT_EQ(refused.status, 2) << refused.out;
  EXPECT_NE(refused.out.find("--admin-token-out"), std::string::npos) << refused.out;
  EXPECT_FALSE(std::filesystem::exists(dir.file("other.db")));
  // A directory no file can be made in (even by root): refused before anything is made too.
  // Found only once the token was made, it was revoked, and a later start made none.
  const CommandResult unwritable =
      RunPintag("serve --port 0 --bind 127.0.0.1 --db " + dir.file("other.db") +
                " --admin-token-out /proc/first-admin.token");
  EXPECT_EQ(unwritable.status, 2) << unwritable.out;
  EXPECT_NE(unwritable.out.find("cannot write in /proc"), std::string::npos) << unwritable.out;
  EXPECT_FALSE(std::filesystem::exists(dir.file("other.db")));
}

// Starts refused before anything is opened or created, each saying what to do instead.
TEST(ServeStartRefusals, AnEmptyBindAddressIsAUsageErrorNotEveryInterface) {
  const TempDir dir;
  const CommandResult refused = RunPintag("serve --port 0 --bind '' --db " + dir.file("new.db"));
  EXPECT_EQ(refused.status, 2) << refused.out;
  EXPECT_NE(refused.out.find("--bind needs an address"), std::string::npos) << refused.out;
  EXPECT_FALSE(std::filesystem::exists(dir.file("new.db")));
}
/// `pintag serve` on loopback with a database `dir` does not hold yet (new.db), as a shell command
/// line to prefix with variables; a refusal must leave no new.db behind.
std::string ServeOnANewDatabase(const TempDir& dir) {
  return "timeout 30 " + PintagExe() + " serve --port 0 --bind 127.0.0.1 --db " +
         dir.file("new.db");
}

// A bad value from an environment variable (a container's PINTAG_THREADS) was named by its flag
// alone, which is on no command line: the variable is named too.
TEST(ServeStartRefusals, ABadValueFromTheEnvironmentNamesItsVariable) {
  const TempDir dir;
  const std::string serve = ServeOnANewDatabase(dir);
  const std::string serve_with_stderr = " " + serve + " 2>&1";  // after a variable's assignment
  CommandResult refused = RunShell("PINTAG_THREADS=0 " + serve + " 2>&1");
  EXPECT_EQ(refused.status, 2) << refused.out;
  EXPECT_NE(refused.out.find("--threads: Value 0 not in range 1 to 256 (the value of the "
                             "environment variable PINTAG_THREADS)"),
            std::string::npos)
      << refused.out;
  refused = RunShell("PINTAG_MAX_BATCH=abc " + serve + " 2>&1");
  EXPECT_EQ(refused.status, 2) << refused.out;
  EXPECT_NE(refused.out.find("PINTAG_MAX_BATCH"), std::string::npos) << refused.out;
  // Given on the command line too, the flag's value is the one refused: the variable is not named.
  refused = RunShell("PINTAG_THREADS=4 " + serve + " --threads 0 2>&1");
  EXPECT_EQ(refused.status, 2) << refused.out;
  EXPECT_NE(refused.out.find("--threads: Value 0"), std::string::npos) << refused.out;
  EXPECT_EQ(refused.out.find("PINTAG_THREADS"), std::string::npos) << refused.out;
  // CLI11's conversion errors, and the server's own checks of a value, name the flag in other
  // words: the variable was not named there.
  for (const auto& [variable, says] : std::vector<std::pair<std::string, std::string>>{
           {"PINTAG_READ_ONLY=banana", "--read-only = banana"},
           {"PINTAG_TRUSTED_PROXY=foo", "--trusted-proxy 'foo' is not an IPv4 or IPv6 address"},
           {"PINTAG_WEB=" + dir.file("no-such-web"), "--web " + dir.file("no-such-web")},
           {"PINTAG_FOLLOW=notaurl", "--follow takes the primary's base URL"}}) {
    refused = RunShell(variable + serve_with_stderr);
    EXPECT_EQ(refused.status, 2) << variable << ": " << refused.out;
    EXPECT_NE(refused.out.find(says), std::string::npos) << refused.out;
    std::string named = "(the value of the environment variable ";
    named.append(variable.substr(0, variable.find('='))).append(")");
    EXPECT_NE(refused.out.find(named), std::string::npos) << refused.out;
  }
  // A replica's option set in a primary's environment (a compose file's shared block) is refused
  // for being given at all: the variable that gave it is named.
  for (const auto& [variable, says] : std::vector<std::pair<std::string, std::string>>{
           {"PINTAG_SCAN_LOG=" + dir.file("scans.db"), "--scan-log is for a replica"},
           {"PINTAG_PRIMARY=http://127.0.0.1:9", "--primary is for a replica"}}) {
    refused = RunShell(variable + serve_with_stderr);
    EXPECT_EQ(refused.status, 2) << variable << ": " << refused.out;
    std::string named = says;
    named.append(" (--read-only or --follow); a primary has no use for it (set by the environment ")
        .append("variable ")
        .append(variable.substr(0, variable.find('=')))
        .append(")");
    EXPECT_NE(refused.out.find(named), std::string::npos) << refused.out;
  }
  // The follower's token, which only the environment gives, was silently unused where nothing
  // follows: refused as --follow-token-file is.
  const std::string token = "PINTAG_FOLLOW_TOKEN=pt_1_" + std::string(43, 'A') + " ";
  refused = RunShell(token + serve + " 2>&1");
  EXPECT_EQ(refused.status, 2) << refused.out;
  EXPECT_NE(refused.out.find("PINTAG_FOLLOW_TOKEN is a replica's token for --follow; a primary "
                             "has no use for it"),
            std::string::npos)
      << refused.out;
  refused = RunShell(token + serve + " --read-only 2>&1");
  EXPECT_EQ(refused.status, 2) << refused.out;
  EXPECT_NE(refused.out.find("this replica follows no one"), std::string::npos) << refused.out;
  EXPECT_FALSE(std::filesystem::exists(dir.file("new.db")));
}

// A follower's token file that holds no token was answered "set PINTAG_FOLLOW_TOKEN or give
// --follow-token-file", given; one that could not be read, with no reason.
TEST(ServeStartRefusals, AFollowTokenFileThatGivesNoTokenSaysWhy) {
  const TempDir dir;
  const std::string serve = ServeOnANewDatabase(dir) + " --follow http://127.0.0.1:9";
  const std::string empty = WriteFile(dir.file("empty.token"), "\n");
  for (const auto& [file, says] : std::vector<std::pair<std::string, std::string>>{
           {empty, "--follow-token-file " + empty + " holds no token"},
           {dir.file("missing.token"), "cannot read --follow-token-file " +
                                           dir.file("missing.token") +
                                           ": No such file or directory"},
           {dir.path().string(),
            "--follow-token-file " + dir.path().string() + " is a directory"}}) {
    std::string line = serve;
    line.append(" --follow-token-file ").append(file).append(" 2>&1");
    const CommandResult refused = RunShell(line);
    EXPECT_EQ(refused.status, 2) << file << ": " << refused.out;
    EXPECT_NE(refused.out.find(says), std::string::npos) << refused.out;
  }
  // A token cut short or mistyped: said at start, where the follower logged the primary's 401
  // at every poll.
  const std::string cut = WriteFile(dir.file("cut.token"), "pt_3_" + std::string(40, 'Q') + "\n");
  const CommandResult from_file = RunShell(serve + " --follow-token-file " + cut + " 2>&1");
  EXPECT_EQ(from_file.status, 2) << from_file.out;
  EXPECT_NE(from_file.out.find("the replica token in --follow-token-file " + cut +
                               " is not a PinTag token's secret"),
            std::string::npos)
      << from_file.out;
  const CommandResult from_env =
      RunShell("PINTAG_FOLLOW_TOKEN=pt_x_" + std::string(43, 'Q') + " " + serve + " 2>&1");
  EXPECT_EQ(from_env.status, 2) << from_env.out;
  EXPECT_NE(from_env.out.find("the replica token in PINTAG_FOLLOW_TOKEN is not"), std::string::npos)
      << from_env.out;
  EXPECT_FALSE(std::filesystem::exists(dir.file("new.db")));
  // Nor a scan log beside it (the replica's own file, which a refused start made before).
  EXPECT_FALSE(std::filesystem::exists(dir.file("new-scans.db")));
}

// CLI11 takes a variable set to "" as unset: `PINTAG_ADMIN_TOKEN_OUT=$UNSET_PATH` printed the first
// admin secret to the log rather than writing it to a file. An empty variable is refused, before a
// database is made; a value on the command line still wins over it, and --help still answers.
TEST(ServeStartRefusals, AnEmptyEnvironmentVariableIsRefusedBeforeAnythingIsMade) {
  const TempDir dir;
  const std::string serve = ServeOnANewDatabase(dir);
  CommandResult refused = RunShell("PINTAG_ADMIN_TOKEN_OUT= " + serve + " 2>&1");
  EXPECT_EQ(refused.status, 2) << refused.out;
  EXPECT_NE(refused.out.find("PINTAG_ADMIN_TOKEN_OUT (--admin-token-out) is set but empty"),
            std::string::npos)
      << refused.out;
  EXPECT_EQ(refused.out.find("secret"), std::string::npos) << refused.out;
  EXPECT_FALSE(std::filesystem::exists(dir.file("new.db")));
  refused = RunShell("PINTAG_FOLLOW= " + serve + " 2>&1");
  EXPECT_EQ(refused.status, 2) << refused.out;
  EXPECT_NE(refused.out.find("PINTAG_FOLLOW (--follow) is set but empty"), std::string::npos)
      << refused.out;
  // --threads 0 on the command line is the error named, not the empty variable behind it.
  refused = RunShell("PINTAG_THREADS= " + serve + " --threads 0 2>&1");
  EXPECT_EQ(refused.status, 2) << refused.out;
  EXPECT_NE(refused.out.find("--threads: Value 0"), std::string::npos) << refused.out;
  const CommandResult help = RunShell("PINTAG_THREADS= " + serve + " --help");
  EXPECT_EQ(help.status, 0) << help.out;
  EXPECT_NE(help.out.find("--threads"), std::string::npos) << help.out;
  // Another command is not held up by serve's variables.
  const CommandResult lookup = RunShell("PINTAG_DB= " + PintagExe() + " keys lookup 110001 --db " +
                                        dir.file("keys.db") + " 2>&1");
  EXPECT_EQ(lookup.status, 0) << lookup.out;
  EXPECT_FALSE(std::filesystem::exists(dir.file("new.db")));
}

// A replica's options on a primary (and a follower's on a replica that follows no one) did
// nothing, without a word (no --scan-log file was made), and a --snapshot naming the database
// itself was retried for ever: usage errors, before the database is created and seeded.
TEST(ServeStartRefusals, OptionsThatContradictTheRoleAreUsageErrors) {
  const TempDir dir;
  const std::string db = dir.file("new.db");
  // Of a token's form (pt_, id, _, 43 characters), so that the role is what is refused.
  const std::string token = WriteFile(dir.path() / "t", "pt_1_" + std::string(43, 'A') + "\n");
  for (const std::string& options :
       {"--scan-log " + dir.file("scans.db"), std::string("--primary http://127.0.0.1:1"),
        "--follow-token-file " + token, "--snapshot " + db, "--snapshot " + db + "-wal",
        "--snapshot " + (dir.path() / "." / "new.db").string(),
        "--read-only --follow-token-file " + token, std::string("--follow-interval-ms 200"),
        std::string("--read-only --follow-interval-ms 200")}) {
    // Bounded: a server that starts regardless would serve until stopped.
    std::string command = "timeout 30 " + PintagExe();
    command += " serve --port 0 --bind 127.0.0.1 --db " + db + " ";
    command += options + " 2>&1";
    const CommandResult refused = RunShell(command);
    EXPECT_EQ(refused.status, 2) << options << ": " << refused.out;
    EXPECT_FALSE(std::filesystem::exists(db)) << options;
    EXPECT_FALSE(std::filesystem::exists(dir.file("scans.db"))) << options;
  }
}

TEST(ServeStartRefusals, AReadOnlyReplicaWithoutItsSnapshotSaysHowToMakeOne) {
  const TempDir dir;
  const CommandResult refused =
      RunPintag("serve --port 0 --read-only --db " + dir.file("missing.db"));
  EXPECT_EQ(refused.status, 1) << refused.out;
  EXPECT_NE(refused.out.find("does not exist: make one on the primary with `pintag snapshot"),
            std::string::npos)
      << refused.out;
  // Nothing is left beside it (no serving link, no scan log).
  EXPECT_TRUE(std::filesystem::is_empty(dir.path())) << refused.out;
}

// A start that cannot listen (port taken) exits non-zero and creates no token nobody would see.
TEST_F(ServeTest, PortInUseFailsWithoutCreatingAToken) {
  const std::string fresh = dir_.file("fresh.db");
  std::filesystem::copy_file(SeededTemplate(), fresh);  // seeded, no tokens
  const std::string command = PintagExe() + " serve --db " + fresh + " --port " +
                              std::to_string(server_->port()) + " 2>" + dir_.file("busy.log");
  FILE* pipe = ::popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string out;
  char buffer[4096];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) out.append(buffer, n);
  const int status = ::pclose(pipe);
  EXPECT_NE(WEXITSTATUS(status), 0);
  EXPECT_TRUE(Secrets(out).empty()) << out;
  EXPECT_NE(ReadFile(dir_.file("busy.log")).find("Address already in use"), std::string::npos)
      << ReadFile(dir_.file("busy.log"));
  auto opened = db::OpenDatabase(fresh, {.create = false});
  ASSERT_TRUE(opened);
  auto tokens = db::ListTokens(opened.value().connection);
  ASSERT_TRUE(tokens);
  EXPECT_TRUE(tokens->empty());

  // Said before a missing database is created and seeded (seconds), and none is left behind.
  const std::string missing = dir_.file("never.db");
  const CommandResult refused =
      RunPintag("serve --db " + missing + " --port " + std::to_string(server_->port()));
  EXPECT_EQ(refused.status, 1) << refused.out;
  EXPECT_NE(refused.out.find("Address already in use"), std::string::npos) << refused.out;
  EXPECT_FALSE(std::filesystem::exists(missing));
}

// Many clients at once: each request leases its own database connection.
TEST_F(ServeTest, ConcurrentClientsGetConsistentAnswers) {
  auto tag = client().Get("/api/v1/tags/110001.png?px=160", counter());
  ASSERT_TRUE(tag && tag->status == 200);
  const std::string png = tag->body;
  std::atomic<int> good{0};
  std::vector<std::thread> threads;
  threads.reserve(8);
  for (int t = 0; t < 8; ++t) {
    threads.emplace_back([&, t] {
      httplib::Client c("127.0.0.1", server_->port());
      c.set_read_timeout(30, 0);
      for (int i = 0; i < 12; ++i) {
        httplib::Result r = (i + t) % 3 == 0 ? c.Get("/api/v1/pincodes/110001")
                            : (i + t) % 3 == 1
                                ? c.Get("/api/v1/labels/560001.svg", counter())
                                : c.Post("/api/v1/detect", scanner(), png, "image/png");
        if (!r || r->status != 200) continue;
        if ((i + t) % 3 == 0 && json::parse(r->body)["key"] != 11684) continue;
        if ((i + t) % 3 == 2 && json::parse(r->body)["tags"][0]["pincode"] != "110001") continue;
        ++good;
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  EXPECT_EQ(good, 96);
  ScanRowsOnceThereAre(db_path_, 32);
  auto opened = db::OpenDatabase(db_path_, {.create = false});
  ASSERT_TRUE(opened);
  auto scans = db::RecentScans(opened.value().connection, 1000);
  ASSERT_TRUE(scans);
  EXPECT_EQ(scans->size(), 32U);  // every detect call logged, none lost to lock contention
}

TEST_F(ServeTest, FixtureServerPrintsNoTokenWhenTokensExist) {
  EXPECT_TRUE(Secrets(server_->out()).empty()) << server_->out();
}

TEST_F(ServeTest, ReadyzFailsWhenTheDatabaseIsUnreachable) {
  ExpectJson(client().Get("/livez"));
  EXPECT_EQ(ExpectJson(client().Get("/readyz"))["status"], "ready");

  // Unreadable by permissions: only meaningful when not root (root reads through mode 000).
  if (::geteuid() != 0) {
    std::filesystem::permissions(db_path_, std::filesystem::perms::none);
    ExpectProblem(client().Get("/readyz"), 503);
    std::filesystem::permissions(
        db_path_, std::filesystem::perms::owner_read | std::filesystem::perms::owner_write);
    ExpectJson(client().Get("/readyz"));
  }
  // Moved away (what an unmounted volume looks like): 503; moved back: ready again.
  std::filesystem::rename(db_path_, db_path_ + ".away");
  json problem = ExpectProblem(client().Get("/readyz"), 503);
  EXPECT_EQ(problem["title"], "Not Ready");
  EXPECT_NE(problem["detail"].get<std::string>().find("missing"), std::string::npos);
  // An open route: what is wrong, not where the file is.
  EXPECT_EQ(problem["detail"].get<std::string>().find(db_path_), std::string::npos) << problem;
  EXPECT_EQ(problem.dump().find(dir_.path().filename().string()), std::string::npos) << problem;
  ExpectJson(client().Get("/livez"));  // the process is still up
  std::filesystem::rename(db_path_ + ".away", db_path_);
  ExpectJson(client().Get("/readyz"));

  // Replaced by a file that is not a database: 503.
  std::filesystem::rename(db_path_, db_path_ + ".away");
  WriteFile(db_path_, std::string(8192, 'z'));
  ExpectProblem(client().Get("/readyz"), 503);
  std::filesystem::remove(db_path_);
  std::filesystem::rename(db_path_ + ".away", db_path_);
  ExpectJson(client().Get("/readyz"));
}

TEST_F(ServeTest, ABackupRestoredUnderARunningServerIsNotUndoneByItsLog) {
  // The operator renames a backup over the served file. The server's connections keep the old
  // file, whose write-ahead log stays beside the new one: writes went on into it (201), and the
  // next open replayed it into the backup (rows it never held, or a corrupt file).
  const auto add = [&](const char* pincode) {
    const auto r =
        client().Post("/api/v1/pincodes", admin(),
                      std::string(R"({"pincode": ")") + pincode + R"("})", "application/json");
    return r ? r->status : -1;
  };
  ASSERT_EQ(add("999030"), 201);
  const std::string backup = dir_.file("backup.db");
  {
    db::Connection live(db_path_, {.create = false});
    live.execute("VACUUM INTO '" + backup + "'");
  }
  ASSERT_EQ(add("999031"), 201);
  std::filesystem::rename(backup, db_path_);

  const auto refused =
      client().Post("/api/v1/pincodes", admin(), R"({"pincode": "999032"})", "application/json");
  EXPECT_EQ(ExpectProblem(refused, 503)["title"], "Database File Replaced");
  ExpectProblem(client().Get("/api/v1/pincodes/110001"), 503);
  ExpectProblem(client().Get("/readyz"), 503);
  EXPECT_EQ(server_->stop(), 0);

  auto opened = db::OpenDatabase(db_path_, {.create = false});
  ASSERT_TRUE(opened) << opened.error().message;
  db::Connection& restored = opened.value().connection;
  db::Statement check = restored.prepare("PRAGMA integrity_check");
  ASSERT_TRUE(check.step());
  EXPECT_EQ(check.getText(0), "ok");
  EXPECT_TRUE(db::LookupPincode(restored, Pincode(999030)));
  for (const std::uint32_t lost : {999031U, 999032U}) {
    EXPECT_FALSE(db::LookupPincode(restored, Pincode(lost))) << lost;
  }
}

TEST_F(ServeTest, ABackupRestoredJustBeforeAStopIsNotUndoneByItsLog) {
  // No request or probe between the restore and the stop: the stop itself must look.
  const auto r =
      client().Post("/api/v1/pincodes", admin(), R"({"pincode": "999030"})", "application/json");
  ASSERT_TRUE(r && r->status == 201);
  const std::string backup = dir_.file("backup.db");
  {
    db::Connection live(db_path_, {.create = false});
    live.execute("VACUUM INTO '" + backup + "'");
  }
  const auto later =
      client().Post("/api/v1/pincodes", admin(), R"({"pincode": "999031"})", "application/json");
  ASSERT_TRUE(later && later->status == 201);
  std::filesystem::rename(backup, db_path_);
  EXPECT_EQ(server_->stop(), 0);

  auto opened = db::OpenDatabase(db_path_, {.create = false});
  ASSERT_TRUE(opened) << opened.error().message;
  db::Connection& restored = opened.value().connection;
  EXPECT_TRUE(db::LookupPincode(restored, Pincode(999030)));
  EXPECT_FALSE(db::LookupPincode(restored, Pincode(999031)));
  EXPECT_NE(ReadFile(dir_.file("stderr.log")).find("were moved into the file this server opened"),
            std::string::npos)
      << ReadFile(dir_.file("stderr.log"));
}

TEST_F(ServeTest, ATokenThatCannotBeCheckedIsUnavailableNotInvalid) {
  // A new process has no database connection open until a request needs one; with the file
  // moved away that first one cannot open, and the token is not at fault: 503, not 401 (a client
  // told its token is invalid may throw a good token away over an outage).
  startServer();
  std::filesystem::rename(db_path_, db_path_ + ".away");
  const auto refused = client().Get("/api/v1/labels/110001.svg", counter());
  ExpectProblem(refused, 503);
  EXPECT_FALSE(refused->has_header("WWW-Authenticate"));
  std::filesystem::rename(db_path_ + ".away", db_path_);
  const auto served = client().Get("/api/v1/labels/110001.svg", counter());
  ASSERT_TRUE(served);
  EXPECT_EQ(served->status, 200);
}

TEST_F(ServeTest, MetricsCountWhatTheTestDid) {
  for (int i = 0; i < 3; ++i) ExpectJson(client().Get("/api/v1/pincodes/110001"));
  for (int i = 0; i < 2; ++i) ExpectProblem(client().Get("/api/v1/pincodes/999999"), 404);
  ExpectProblem(client().Get("/api/v1/pincodes/12"), 400);
  for (int i = 0; i < 2; ++i) {
    auto r = client().Get("/api/v1/labels/110001.svg", counter());
    ASSERT_TRUE(r && r->status == 200);
  }
  auto r = client().Post("/api/v1/labels", counter(),
                         R"({"pincodes": ["110001", "560001", "400001"]})", "application/json");
  ASSERT_TRUE(r && r->status == 200);
  r = client().Get("/api/v1/tags/110001.png", counter());
  ASSERT_TRUE(r && r->status == 200);
  // A detection of a real tag.
  r = client().Get("/api/v1/tags/110001.png?px=200", counter());
  ASSERT_TRUE(r && r->status == 200);
  const json detected =
      ExpectJson(client().Post("/api/v1/detect", scanner(), r->body, "image/png"));
  ASSERT_EQ(detected["tags"].size(), 1U) << detected.dump();
  ExpectProblem(client().Post("/api/v1/detect", scanner(), "nope", "image/png"), 415);

  // cpp-httplib's logger, which counts a request, runs after the response is sent, on whichever
  // worker thread served it: wait until all 13 requests above are counted (the deadline only
  // keeps a broken server from hanging the test), then check each series.
  std::string m;
  const auto requests = [&](const std::string& route, const std::string& method, int status) {
    return Metric(m, "pintag_http_requests_total{route=\"" + route + "\",method=\"" + method +
                         "\",status=\"" + std::to_string(status) + "\"}");
  };
  const auto counted = [&] {
    return requests("/api/v1/pincodes/{pin}", "GET", 200) +
           requests("/api/v1/pincodes/{pin}", "GET", 404) +
           requests("/api/v1/pincodes/{pin}", "GET", 400) +
           requests("/api/v1/labels/{pin}.svg", "GET", 200) +
           requests("/api/v1/labels", "POST", 200) +
           requests("/api/v1/tags/{pin}.png", "GET", 200) +
           requests("/api/v1/detect", "POST", 200) + requests("/api/v1/detect", "POST", 415);
  };
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (std::chrono::steady_clock::now() < deadline) {
    r = client().Get("/metrics");
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 200);
    m = r->body;
    if (counted() >= 13) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_EQ(requests("/api/v1/pincodes/{pin}", "GET", 200), 3);
  EXPECT_EQ(requests("/api/v1/pincodes/{pin}", "GET", 404), 2);
  EXPECT_EQ(requests("/api/v1/pincodes/{pin}", "GET", 400), 1);
  EXPECT_EQ(requests("/api/v1/labels/{pin}.svg", "GET", 200), 2);
  EXPECT_EQ(requests("/api/v1/labels", "POST", 200), 1);
  EXPECT_EQ(requests("/api/v1/tags/{pin}.png", "GET", 200), 2);
  EXPECT_EQ(requests("/api/v1/detect", "POST", 200), 1);
  EXPECT_EQ(requests("/api/v1/detect", "POST", 415), 1);
  EXPECT_EQ(Metric(m, "pintag_labels_rendered_total"), 5);  // 2 SVGs + 3 PDF pages
  EXPECT_EQ(Metric(m, "pintag_tags_rendered_total"), 2);
  EXPECT_EQ(Metric(m, "pintag_detections_total"), 1);
  EXPECT_EQ(Metric(m, "pintag_scans_total"), 2);
  EXPECT_EQ(Metric(m, "pintag_detections_unknown_key_total"), 0);
  EXPECT_EQ(Metric(m,
                   "pintag_http_request_duration_seconds_count{route=\"/api/v1/pincodes/{pin}\","
                   "method=\"GET\",status=\"200\"}"),
            3);
}

// Every route the OpenAPI document lists answers (no 404 "no route", no 405), and every route
// issue 5 names is listed.
TEST_F(ServeTest, OpenApiListsEveryRouteAndEachAnswers) {
  const json doc = ExpectJson(client().Get("/openapi.json"));
  EXPECT_EQ(doc["openapi"].get<std::string>().rfind("3.1", 0), 0U);
  std::set<std::string> listed;
  for (const auto& [path, item] : doc["paths"].items()) {
    for (const auto& [method, operation] : item.items()) {
      if (method == "parameters") continue;
      const std::string upper = Upper(method);
      listed.insert(std::string(upper).append(" ").append(path));
      std::string concrete = std::regex_replace(path, std::regex(R"(\{pin\})"), "110001");
      concrete = std::regex_replace(concrete, std::regex(R"(\{key\})"), "11684");
      concrete = std::regex_replace(concrete, std::regex(R"(\{name\})"), "default");
      concrete =
          std::regex_replace(concrete, std::regex(R"(\{id\})"), std::to_string(counter_token_id_));
      const bool image = concrete == "/api/v1/detect";
      httplib::Result r =
          upper == "GET"    ? client().Get(concrete, admin())
          : upper == "POST" ? client().Post(concrete, admin(), image ? "x" : "{}",
                                            image ? "image/jpeg" : "application/json")
          : upper == "PUT"  ? client().Put(concrete, admin(), "{}", "application/json")
                            : client().Delete(concrete, admin());
      EXPECT_TRUE(upper == "GET" || upper == "POST" || upper == "PUT" || upper == "DELETE")
          << upper;
      ASSERT_TRUE(r) << upper << " " << concrete;
      EXPECT_NE(r->status, 405) << upper << " " << concrete;
      EXPECT_NE(r->status, 501) << upper << " " << concrete;
      EXPECT_EQ(r->body.find("no route for"), std::string::npos) << upper << " " << concrete;
      EXPECT_LT(r->status, 500) << upper << " " << concrete << " " << r->body;
      if (r->status < 300) {
        EXPECT_TRUE(operation["responses"].contains(std::to_string(r->status)))
            << upper << " " << concrete << " answered " << r->status << ", not documented";
      }
    }
  }
  // The routes that create answer 201 Created, and say so (every success was documented as 200).
  const auto created =
      client().Post("/api/v1/tokens", admin(), R"({"role": "scanner"})", "application/json");
  ASSERT_TRUE(created);
  EXPECT_EQ(created->status, 201);
  for (const char* path : {"/api/v1/tokens", "/api/v1/pincodes"}) {
    const json& responses = doc["paths"][path]["post"]["responses"];
    EXPECT_TRUE(responses.contains("201")) << path;
    EXPECT_FALSE(responses.contains("200")) << path;
  }
  const json& put_plan = doc["paths"]["/api/v1/sortplans/{name}"]["put"]["responses"];
  EXPECT_TRUE(put_plan.contains("200") && put_plan.contains("201")) << put_plan;
  // Every success was described as "Error" (the problem titles' fallback).
  for (const auto& [path, item] : doc["paths"].items()) {
    for (const auto& [method, operation] : item.items()) {
      for (const auto& [status, response] : operation["responses"].items()) {
        EXPECT_NE(response["description"], "Error") << method << " " << path << " " << status;
      }
    }
  }
  EXPECT_EQ(put_plan["201"]["description"], "Created");
  // The conditional requests a client needs: 304 (no body) where If-None-Match can bring one, the
  // headers to send, and the ETag to send back; the Location of a new pincode.
  const json& get_plan = doc["paths"]["/api/v1/sortplans/{name}"]["get"];
  const json& get_snapshot = doc["paths"]["/api/v1/registry/snapshot"]["get"];
  for (const json* operation : {&get_plan, &get_snapshot}) {
    ASSERT_TRUE((*operation)["responses"].contains("304")) << *operation;
    EXPECT_FALSE((*operation)["responses"]["304"].contains("content")) << *operation;
    EXPECT_TRUE((*operation)["responses"]["200"]["headers"].contains("ETag")) << *operation;
  }
  const auto reads_header = [](const json& operation, const std::string& name) {
    for (const json& parameter : operation["parameters"]) {
      if (parameter["in"] == "header" && parameter["name"] == name) return true;
    }
    return false;
  };
  EXPECT_TRUE(reads_header(get_plan, "If-None-Match"));
  EXPECT_TRUE(reads_header(get_snapshot, "If-None-Match"));
  const json& put_plan_operation = doc["paths"]["/api/v1/sortplans/{name}"]["put"];
  EXPECT_TRUE(reads_header(put_plan_operation, "If-Match"));
  EXPECT_TRUE(reads_header(put_plan_operation, "If-None-Match"));
  EXPECT_TRUE(reads_header(doc["paths"]["/api/v1/sortplans/{name}"]["delete"], "If-Match"));
  EXPECT_TRUE(
      doc["paths"]["/api/v1/pincodes"]["post"]["responses"]["201"]["headers"].contains("Location"));
  EXPECT_NE(doc["info"]["description"].get<std::string>().find("replica ("), std::string::npos);
  for (const char* route : {"GET /api/v1/pincodes/{pin}",
                            "GET /api/v1/pincodes",
                            "GET /api/v1/keys/{key}",
                            "POST /api/v1/pincodes",
                            "POST /api/v1/pincodes/{pin}/retire",
                            "GET /api/v1/tags/{pin}.png",
                            "GET /api/v1/tags/{pin}.svg",
                            "GET /api/v1/labels/{pin}.pdf",
                            "GET /api/v1/labels/{pin}.png",
                            "GET /api/v1/labels/{pin}.svg",
                            "POST /api/v1/labels",
                            "POST /api/v1/detect",
                            "GET /api/v1/route/{pin}",
                            "GET /api/v1/sortplans",
                            "GET /api/v1/sortplans/{name}",
                            "PUT /api/v1/sortplans/{name}",
                            "DELETE /api/v1/sortplans/{name}",
                            "POST /api/v1/tokens",
                            "GET /api/v1/tokens",
                            "DELETE /api/v1/tokens/{id}",
                            "POST /api/v1/tokens/{id}/revoke",
                            "GET /api/v1/registry",
                            "GET /api/v1/registry/snapshot",
                            "GET /livez",
                            "GET /readyz",
                            "GET /metrics",
                            "GET /openapi.json"}) {
    EXPECT_EQ(listed.count(route), 1U) << route;
  }
  EXPECT_EQ(listed.size(), 27U);
}

// docs/API.md's route table is the route table: every operation /openapi.json lists, with the role
// it needs, is one row there, and the doc lists nothing else.
TEST_F(ServeTest, ApiDocListsEveryRouteWithItsRole) {
  const json doc = ExpectJson(client().Get("/openapi.json"));
  std::set<std::string> served;
  for (const auto& [path, item] : doc["paths"].items()) {
    for (const auto& [method, operation] : item.items()) {
      served.insert(Upper(method).append(" ").append(path).append(" ").append(
          operation["x-pintag-role"].get<std::string>()));
    }
  }
  const std::string text = ReadFile(std::string(PINTAG_SOURCE_DIR) + "/docs/API.md");
  const std::size_t begin = text.find("<!-- routes:");
  const std::size_t end = text.find("<!-- /routes -->");
  ASSERT_NE(begin, std::string::npos);
  ASSERT_NE(end, std::string::npos);
  std::set<std::string> documented;
  const std::string table = text.substr(begin, end - begin);
  const std::regex row(
      R"(\| (GET|POST|PUT|DELETE) \| `([^`]+)` \| (open|counter|scanner|replica|admin) \|)");
  for (auto it = std::sregex_iterator(table.begin(), table.end(), row);
       it != std::sregex_iterator(); ++it) {
    EXPECT_TRUE(
        documented.insert((*it)[1].str() + " " + (*it)[2].str() + " " + (*it)[3].str()).second)
        << "listed twice: " << it->str();
  }
  for (const std::string& route : served) {
    EXPECT_EQ(documented.count(route), 1U) << "docs/API.md does not list " << route;
  }
  for (const std::string& route : documented) {
    EXPECT_EQ(served.count(route), 1U) << "docs/API.md lists " << route << ", not served";
  }
}

TEST_F(ServeTest, StaticFilesFromTheWebDirectoryOnly) {
  std::filesystem::create_directories(dir_.path() / "web");
  WriteFile(dir_.file("web/index.html"), "<h1>PinTag</h1>");
  WriteFile(dir_.file("outside.txt"), "SECRET");
  startServer({"--web", dir_.file("web")});
  auto r = client().Get("/");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200);
  EXPECT_EQ(r->body, "<h1>PinTag</h1>");
  for (const char* path : {"/../outside.txt", "/%2e%2e/outside.txt", "/..%2foutside.txt"}) {
    r = client().Get(path);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 404) << path;
    EXPECT_EQ(r->body.find("SECRET"), std::string::npos);
  }
  ExpectProblem(client().Get("/api/v1/nothing"), 404);
}

// A request whose body is still arriving when SIGTERM comes is read to the end and answered;
// then the process exits 0 and the port is closed. No sleeps: the server shows it has read the
// headers by asking for the body (100 Continue), and that it is stopping by refusing new
// connections, before the rest of the body is sent.
TEST_F(ServeTest, SigtermFinishesTheRequestInFlightThenExits) {
  const std::string body = R"({"pincodes": ["110001", "560001"], "size": "a6"})";
  const int fd = test::ConnectLoopback(server_->port());
  ASSERT_GE(fd, 0);
  const std::string head =
      "POST /api/v1/labels HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer " + counter_token_ +
      "\r\nContent-Type: application/json\r\nExpect: 100-continue\r\nContent-Length: " +
      std::to_string(body.size()) + "\r\n\r\n";
  test::SendAll(fd, head);
  const std::string go_on = test::ReceiveUntil(
      fd, 30, [](const std::string& out) { return out.find("\r\n\r\n") != std::string::npos; });
  ASSERT_EQ(go_on.rfind("HTTP/1.1 100", 0), 0U) << go_on;
  test::SendAll(fd, body.substr(0, 10));
  server_->signal(SIGTERM);  // the request is half read
  bool refusing = false;
  for (const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
       !refusing && std::chrono::steady_clock::now() < deadline;) {
    const int probe = test::ConnectLoopback(server_->port());
    refusing = probe < 0;
    if (probe >= 0) ::close(probe);
    if (!refusing) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_TRUE(refusing) << "the server still accepts connections 30 s after SIGTERM";
  const std::string rest = body.substr(10);
  test::SendAll(fd, rest);
  const std::string answer = test::ReceiveUntil(fd, 10);
  ::close(fd);
  EXPECT_EQ(answer.rfind("HTTP/1.1 200", 0), 0U) << answer.substr(0, 300);
  EXPECT_NE(answer.find("%PDF-"), std::string::npos);
  // The answer says the connection ends, so that the client does not send another request on it.
  const std::string answer_head = answer.substr(0, answer.find("\r\n\r\n"));
  EXPECT_NE(answer_head.find("\r\nConnection: close"), std::string::npos) << answer_head;
  EXPECT_EQ(answer_head.find("Keep-Alive"), std::string::npos) << answer_head;
  EXPECT_EQ(server_->wait(30), 0);  // a second SIGTERM would cut the drain short
  EXPECT_NE(ReadFile(dir_.file("stderr.log")).find("stopped"), std::string::npos);
  httplib::Client after("127.0.0.1", server_->port());
  after.set_connection_timeout(1, 0);
  EXPECT_FALSE(after.Get("/livez"));
}

// A stop waits for requests in flight, but not for ever: a second SIGTERM or SIGINT ends the
// process at once, and --drain-timeout bounds the wait. A client sending its upload slowly held
// the exit for as long as it kept sending, and further signals were ignored.
class SlowUploadWhileStopping : public ServeTest {
 protected:
  // Starts an upload the server is reading (it asked for the body), then SIGTERM; returns the
  // connection, the body never finished.
  int startUploadThenStop() {
    const int fd = test::ConnectLoopback(server_->port());
    EXPECT_GE(fd, 0);
    test::SendAll(fd, "POST /api/v1/detect HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer " +
                          scanner_token_ +
                          "\r\nContent-Type: image/jpeg\r\nExpect: 100-continue\r\n"
                          "Content-Length: 100000\r\n\r\n");
    const std::string go_on = test::ReceiveUntil(
        fd, 30, [](const std::string& out) { return out.find("\r\n\r\n") != std::string::npos; });
    EXPECT_EQ(go_on.rfind("HTTP/1.1 100", 0), 0U) << go_on;
    test::SendAll(fd, std::string(100, 'x'));
    server_->signal(SIGTERM);
    return fd;
  }
  // Keeps the upload alive, a little at a time, while `until` does not hold (at most 60 s).
  void trickle(int fd, const std::function<bool()>& until) {
    for (const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
         !until() && std::chrono::steady_clock::now() < deadline;) {
      test::SendAll(fd, std::string(10, 'x'));
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
  }
};

TEST_F(SlowUploadWhileStopping, ASecondSignalStopsAtOnce) {
  const int fd = startUploadThenStop();
  // The first signal was taken (the drain began) once the port refuses connections.
  trickle(fd, [&] {
    const int probe = test::ConnectLoopback(server_->port());
    if (probe >= 0) ::close(probe);
    return probe < 0;
  });
  EXPECT_TRUE(server_->running()) << "the upload in flight is still being read";
  const auto sent = std::chrono::steady_clock::now();
  EXPECT_EQ(server_->stop(SIGINT, 20), 128 + SIGINT);
  EXPECT_LT(std::chrono::steady_clock::now() - sent, std::chrono::seconds(5));
  ::close(fd);
  EXPECT_NE(ReadFile(dir_.file("stderr.log")).find("SIGINT again: stopping now"), std::string::npos)
      << ReadFile(dir_.file("stderr.log"));
}

TEST_F(SlowUploadWhileStopping, TheDrainTimeoutEndsTheWait) {
  startServer({"--drain-timeout", "2"});
  const int fd = startUploadThenStop();
  const auto signalled = std::chrono::steady_clock::now();
  trickle(fd, [&] { return !server_->running(); });
  const auto waited = std::chrono::steady_clock::now() - signalled;
  ::close(fd);
  EXPECT_EQ(server_->wait(5), 1);
  EXPECT_GE(waited, std::chrono::milliseconds(1900));
  EXPECT_LT(waited, std::chrono::seconds(15)) << "the upload held the exit";
  EXPECT_NE(ReadFile(dir_.file("stderr.log")).find("still in flight after 2 s"), std::string::npos)
      << ReadFile(dir_.file("stderr.log"));
}

// A client that stops sending mid-request is answered 400 after the read timeout
// (--read-timeout), not waited for; other clients are served meanwhile.
TEST_F(ServeTest, ReadTimeoutAnswersASilentClient) {
  startServer({"--read-timeout", "1"});
  const int fd = test::ConnectLoopback(server_->port());
  ASSERT_GE(fd, 0);
  const std::string partial = "GET /api/v1/pincodes/110001 HTTP/1.1\r\nHost: x\r\n";
  test::SendAll(fd, partial);
  ExpectJson(client().Get("/api/v1/pincodes/110001"));  // not blocked by the silent one
  const auto start = std::chrono::steady_clock::now();
  const std::string answer = test::ReceiveUntil(
      fd, 10, [](const std::string& out) { return out.find('}') != std::string::npos; });
  const double waited =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ::close(fd);
  // 408 since 2026-12-06, when heads began to be awaited outside the workers (it was 400).
  EXPECT_EQ(answer.rfind("HTTP/1.1 408", 0), 0U) << answer;
  EXPECT_NE(answer.find("application/problem+json"), std::string::npos) << answer;
  // The flag took effect: well before the 5 s default, with room for a loaded machine.
  EXPECT_LT(waited, 4.5);
}

TEST_F(ServeTest, SigintStopsToo) {
  EXPECT_EQ(server_->stop(SIGINT, 20), 0);
}

}  // namespace
}  // namespace pintag::serve_test
