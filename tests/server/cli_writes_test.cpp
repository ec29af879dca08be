// A `pintag` command whose output cannot be written fails (exit 1, saying so) instead of reporting
// success. /dev/full stands in for a full disk: opening it works, every write fails with ENOSPC.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "held_write_lock.hpp"
#include "pintag/db/sqlite.hpp"
#include "pintag/db/tokens.hpp"
#include "serve_fixture.hpp"

namespace pintag::serve_test {
namespace {

constexpr const char* kFull = "/dev/full";

TEST(CliWrites, RenderToAFullDiskFailsForPngAsForSvg) {
  ASSERT_TRUE(std::filesystem::exists(kFull)) << "the full disk these tests write to";
  const TempDir dir;
  for (const char* name : {"full.png", "full.svg"}) {
    const std::string path = dir.file(name);
    std::filesystem::create_symlink(kFull, path);
    const CommandResult run = RunPintag("render --key 1 --size-px 100 -o " + path);
    EXPECT_EQ(run.status, 1) << name << ": " << run.out;
    EXPECT_NE(run.out.find("cannot write"), std::string::npos) << name << ": " << run.out;
    EXPECT_EQ(run.out.find("wrote key"), std::string::npos) << name << ": " << run.out;
  }
  // The same command to a real file still writes a PNG.
  const std::string png = dir.file("tag.png");
  const CommandResult written = RunPintag("render --key 1 --size-px 100 -o " + png);
  EXPECT_EQ(written.status, 0) << written.out;
  EXPECT_EQ(ReadFile(png).substr(0, 8), "\x89PNG\r\n\x1a\n");
}

// A directory that is not there is a mistyped path, said before the work (for the largest tag,
// seconds and 1.7 GB of drawing that ended in exit 1), as `detect --overlay` says it.
TEST(CliWrites, AnOutputInADirectoryThatIsNotThereIsAUsageErrorBeforeTheWork) {
  const TempDir dir;
  const std::string missing = dir.file("no-such-dir");
  const CommandResult render =
      RunPintag("render --key 5 --size-px 16384 -o " + missing + "/big.png");
  EXPECT_EQ(render.status, 2) << render.out;
  EXPECT_NE(render.out.find(missing + " is not a directory"), std::string::npos) << render.out;
  const std::string db = dir.file("copy.db");
  std::filesystem::copy_file(SeededTemplate(), db);
  const CommandResult snapshot = RunPintag("snapshot --db " + db + " --out " + missing + "/s.db");
  EXPECT_EQ(snapshot.status, 2) << snapshot.out;
  EXPECT_NE(snapshot.out.find(missing + " is not a directory"), std::string::npos) << snapshot.out;
}

// A write that failed partway left the output cut short where a good file had been. It is
// written beside and renamed over, so the file before stays whole, and nothing is left beside it.
TEST(CliWrites, AWriteThatFailsLeavesTheFileThereBeforeWhole) {
  const TempDir dir;
  const std::string png = dir.file("tag.png");
  ASSERT_EQ(RunPintag("render --key 1 --size-px 400 -o " + png).status, 0);
  std::filesystem::permissions(png, std::filesystem::perms(0640));
  const std::string before = ReadFile(png);
  ASSERT_GT(before.size(), std::size_t{4096});
  // A file size limit of 4 KiB (ulimit -f counts 512-byte blocks), its signal ignored: a write
  // past it fails with EFBIG, as one on a full disk fails.
  const CommandResult cut = RunShell("trap '' XFSZ; ulimit -f 8; " + PintagExe() +
                                     " render --key 2 --size-px 400 -o " + png + " 2>&1");
  EXPECT_EQ(cut.status, 1) << cut.out;
  EXPECT_NE(cut.out.find("cannot write"), std::string::npos) << cut.out;
  EXPECT_EQ(ReadFile(png), before);
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    ++files;
  }
  EXPECT_EQ(files, 1U) << "a temporary file was left beside the output";
  // Written whole, through a link: the file it names is replaced with its mode, the link kept.
  const std::string link = dir.file("link.png");
  std::filesystem::create_symlink(png, link);
  const CommandResult written = RunPintag("render --key 3 --size-px 400 -o " + link);
  ASSERT_EQ(written.status, 0) << written.out;
  EXPECT_TRUE(std::filesystem::is_symlink(link));
  EXPECT_NE(ReadFile(png), before);
  EXPECT_EQ(ReadFile(link), ReadFile(png));
  EXPECT_EQ(std::filesystem::status(png).permissions() & std::filesystem::perms::all,
            std::filesystem::perms(0640));
}

TEST(CliWrites, KeysExportToAFullDiskFails) {
  ASSERT_TRUE(std::filesystem::exists(kFull)) << "the full disk these tests write to";
  const TempDir dir;
  const std::string db = dir.file("copy.db");
  std::filesystem::copy_file(SeededTemplate(), db);
  const CommandResult run = RunPintagWithStdoutTo("keys export --db " + db, kFull);
  EXPECT_EQ(run.status, 1) << run.out;
  EXPECT_NE(run.out.find("cannot write the key table"), std::string::npos) << run.out;
}

// Every token in the database at `db` (the one just made among them) is revoked: nobody holds a
// usable secret that was never shown.
void ExpectOneAdminTokenRevoked(const TempDir& dir, const std::string& db) {
  const CommandResult list = RunPintagWithStdoutTo("token list --db " + db, dir.file("list.csv"));
  ASSERT_EQ(list.status, 0) << list.out;
  std::istringstream rows(ReadFile(dir.file("list.csv")));
  std::string row;
  std::getline(rows, row);
  ASSERT_EQ(row, "id,role,label,created_at,revoked_at");
  int tokens = 0;
  while (std::getline(rows, row)) {
    ++tokens;
    EXPECT_NE(row.back(), ',') << "not revoked: " << row;
    EXPECT_NE(row.find(",admin,"), std::string::npos) << row;
  }
  EXPECT_EQ(tokens, 1);
}

// A token's label is free text an admin typed; the list is opened in spreadsheets, which run a
// cell starting with = + - or @ as a formula (=HYPERLINK(...) sent its reader to a web page).
TEST(CliWrites, TokenListLabelsReadAsTextInASpreadsheet) {
  const TempDir dir;
  const std::string db = dir.file("copy.db");
  std::filesystem::copy_file(SeededTemplate(), db);
  for (const char* label : {"=HYPERLINK(\"http://x\",\"y\")", "+1", "-2", "@SUM(1)", "plain"}) {
    const CommandResult made = RunPintag("token create --role scanner --db " + db + " --label '" +
                                         std::string(label) + "'");
    ASSERT_EQ(made.status, 0) << made.out;
  }
  const CommandResult list = RunPintagWithStdoutTo("token list --db " + db, dir.file("list.csv"));
  ASSERT_EQ(list.status, 0) << list.out;
  const std::string csv = ReadFile(dir.file("list.csv"));
  EXPECT_NE(csv.find(R"csv(,"'=HYPERLINK(""http://x"",""y"")",)csv"), std::string::npos) << csv;
  for (const char* cell : {",'+1,", ",'-2,", ",'@SUM(1),", ",plain,"}) {
    EXPECT_NE(csv.find(cell), std::string::npos) << cell << " in\n" << csv;
  }
}

TEST(CliWrites, ATokenWhoseSecretCannotBeWrittenIsRevoked) {
  ASSERT_TRUE(std::filesystem::exists(kFull)) << "the full disk these tests write to";
  const TempDir dir;
  const std::string db = dir.file("copy.db");
  std::filesystem::copy_file(SeededTemplate(), db);
  const CommandResult run = RunPintagWithStdoutTo("token create --role admin --db " + db, kFull);
  EXPECT_EQ(run.status, 1) << run.out;
  EXPECT_NE(run.out.find("the token is revoked"), std::string::npos) << run.out;
  ExpectOneAdminTokenRevoked(dir, db);
}

// `token create --out FILE` (a replica's --follow-token-file): the secret in a file only its owner
// may read, replaced whole, nothing on stdout; a directory that is not there, or that cannot be
// written, is a usage error before any token is made.
TEST(CliWrites, ATokenWrittenToAFileIsItsOwnersAloneAndReplacedWhole) {
  const TempDir dir;
  const std::string db = dir.file("copy.db");
  std::filesystem::copy_file(SeededTemplate(), db);
  const std::filesystem::path secrets = dir.path() / "secrets";
  std::filesystem::create_directory(secrets);
  const std::string file = (secrets / "replica.token").string();
  const auto create = [&](const std::string& out) {
    return RunPintagWithStdoutTo(
        "token create --role replica --label r --out " + out + " --db " + db,
        dir.file("stdout.txt"));
  };
  const auto secret_in = [](const std::string& path) {
    const std::string text = ReadFile(path);
    EXPECT_EQ(text.rfind("pt_", 0), 0U) << text;
    EXPECT_EQ(text.back(), '\n');
    return text.substr(0, text.size() - 1);
  };
  const CommandResult first = create(file);
  ASSERT_EQ(first.status, 0) << first.out;
  EXPECT_EQ(ReadFile(dir.file("stdout.txt")), "");
  EXPECT_NE(first.out.find("its secret is in " + file), std::string::npos) << first.out;
  EXPECT_EQ(std::filesystem::status(file).permissions(),
            std::filesystem::perms::owner_read | std::filesystem::perms::owner_write);
  const std::string first_secret = secret_in(file);
  db::Connection connection(db, {.create = false, .read_only = true});
  const auto verified = db::VerifyToken(connection, first_secret);
  ASSERT_TRUE(verified.ok()) << verified.error().message;
  EXPECT_EQ(verified->role, db::Role::kReplica);

  // A second one replaces the first whole, still 0600 (even over a file others could read), and
  // leaves nothing beside it.
  std::filesystem::permissions(file, std::filesystem::perms(0644));
  ASSERT_EQ(create(file).status, 0);
  EXPECT_NE(secret_in(file), first_secret);
  EXPECT_TRUE(db::VerifyToken(connection, secret_in(file)).ok());
  EXPECT_EQ(std::filesystem::status(file).permissions(),
            std::filesystem::perms::owner_read | std::filesystem::perms::owner_write);
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(secrets),
                          std::filesystem::directory_iterator()),
            1);

  const auto token_count = [&] { return connection.queryInt64("SELECT count(*) FROM api_tokens"); };
  const std::int64_t before = token_count();
  const CommandResult missing = create((dir.path() / "no-such-dir" / "t").string());
  EXPECT_EQ(missing.status, 2) << missing.out;
  EXPECT_NE(missing.out.find("is not a directory"), std::string::npos) << missing.out;
  EXPECT_EQ(create(secrets.string()).status, 2);
  EXPECT_EQ(token_count(), before);

  // /proc takes no new files, not even from root: said before a token is made (one was made, and
  // then revoked), as serve --admin-token-out says it.
  const CommandResult unwritable = create("/proc/pintag-secret");
  EXPECT_EQ(unwritable.status, 2) << unwritable.out;
  EXPECT_NE(unwritable.out.find("--out /proc/pintag-secret: cannot write in /proc"),
            std::string::npos)
      << unwritable.out;
  EXPECT_EQ(token_count(), before);
  // Nor is a database made and seeded for it.
  const CommandResult no_db =
      RunPintag("token create --role admin --out /proc/pintag-secret --db " + dir.file("new.db"));
  EXPECT_EQ(no_db.status, 2) << no_db.out;
  EXPECT_FALSE(std::filesystem::exists(dir.file("new.db")));
}

// The secret and the snapshot are written beside their file and renamed into place. Through a
// symbolic link that replaced the link itself (a mounted secret's link, /dev/stdout), and over a
// device or a pipe it put a file in its place and said it had written there.
TEST(CliWrites, TokenAndSnapshotFilesAreWrittenThroughLinksAndNeverReplaceAPipe) {
  const TempDir dir;
  const std::string db = dir.file("copy.db");
  std::filesystem::copy_file(SeededTemplate(), db);
  db::Connection connection(db, {.create = false, .read_only = true});
  const auto token_count = [&] { return connection.queryInt64("SELECT count(*) FROM api_tokens"); };

  // A link to a file there, and one to a file not there yet: the file is written, the link kept.
  const std::string kept = dir.file("kept.token");
  WriteFile(kept, "old\n");
  std::filesystem::create_symlink("kept.token", dir.file("to-kept"));
  std::filesystem::create_symlink("new.token", dir.file("to-new"));
  for (const std::string link : {"to-kept", "to-new"}) {
    const CommandResult made =
        RunPintag("token create --role replica --out " + dir.file(link) + " --db " + db);
    ASSERT_EQ(made.status, 0) << made.out;
    EXPECT_TRUE(std::filesystem::is_symlink(dir.file(link))) << link;
    const std::string secret = ReadFile(dir.file(link));
    EXPECT_TRUE(db::VerifyToken(connection, secret.substr(0, secret.size() - 1)).ok()) << link;
  }
  EXPECT_EQ(std::filesystem::status(dir.file("new.token")).permissions(),
            std::filesystem::perms::owner_read | std::filesystem::perms::owner_write);

  std::filesystem::create_symlink("registry.snap", dir.file("to-snapshot"));
  const CommandResult snapshot =
      RunPintag("snapshot --db " + db + " --out " + dir.file("to-snapshot"));
  ASSERT_EQ(snapshot.status, 0) << snapshot.out;
  EXPECT_TRUE(std::filesystem::is_symlink(dir.file("to-snapshot")));
  const CommandResult verified = RunPintag("snapshot --verify " + dir.file("registry.snap"));
  EXPECT_EQ(verified.status, 0) << verified.out;

  // A link into a directory that is not there: said before any work, naming both paths.
  std::filesystem::create_symlink("no-such-dir/x.token", dir.file("to-nowhere"));
  const std::int64_t tokens_before = token_count();
  const CommandResult nowhere =
      RunPintag("token create --role replica --out " + dir.file("to-nowhere") + " --db " + db);
  EXPECT_EQ(nowhere.status, 2) << nowhere.out;
  EXPECT_NE(nowhere.out.find("--out " + dir.file("to-nowhere") + ", a link to"), std::string::npos)
      << nowhere.out;
  EXPECT_EQ(token_count(), tokens_before);

  // A pipe is refused before any work: no token made, the pipe left a pipe.
  const std::string pipe = dir.file("pipe");
  ASSERT_EQ(::mkfifo(pipe.c_str(), 0600), 0);
  const std::int64_t before = token_count();
  const std::vector<std::string> to_the_pipe = {
      "token create --role replica --out " + pipe + " --db " + db,
      "snapshot --db " + db + " --out " + pipe};
  for (const std::string& command : to_the_pipe) {
    const CommandResult refused = RunPintag(command);
    EXPECT_EQ(refused.status, 2) << command << "\n" << refused.out;
    EXPECT_NE(refused.out.find(pipe + " is a pipe, not a file"), std::string::npos) << refused.out;
  }
  EXPECT_EQ(token_count(), before);
  EXPECT_TRUE(std::filesystem::is_fifo(pipe));
}

// `token create --out pintag.db` (the default --db) wrote the secret over the registry and said
// it had done well; `serve --admin-token-out` named as the database did the same on a first start.
// The database, by any name, its -wal file, and any other SQLite file are refused before any
// work, and left as they were.
TEST(CliWrites, ASecretFileIsNeverADatabase) {
  const TempDir dir;
  const std::string db = dir.file("registry.db");
  std::filesystem::copy_file(SeededTemplate(), db);
  const std::string other = dir.file("other.db");
  std::filesystem::copy_file(SeededTemplate(), other);
  std::filesystem::create_symlink("registry.db", dir.file("to-registry"));
  std::filesystem::create_hard_link(db, dir.file("second-name.db"));
  const std::string before = ReadFile(db);
  const std::string other_before = ReadFile(other);
  for (const auto& [out, says] : std::vector<std::pair<std::string, std::string>>{
           {db, "is the database (--db " + db + ")"},
           {dir.file("to-registry"), "is the database"},
           {dir.file("second-name.db"), "is the database"},
           {dir.path().string() + "/./registry.db", "is the database"},
           {db + "-wal", "is a file of the database " + db},
           {other + "-shm", "is a file of the database " + other},
           {other, "holds an SQLite database"}}) {
    std::string command = "token create --role replica --out ";
    command.append(out).append(" --db ").append(db);
    const CommandResult refused = RunPintag(command);
    EXPECT_EQ(refused.status, 2) << out << "\n" << refused.out;
    std::string said = "--out ";
    said.append(out).append(" ").append(says);
    EXPECT_NE(refused.out.find(said), std::string::npos) << refused.out;
  }
  EXPECT_EQ(ReadFile(db), before);
  EXPECT_EQ(ReadFile(other), other_before);
  EXPECT_FALSE(std::filesystem::exists(db + "-wal"));
  db::Connection connection(db, {.create = false, .read_only = true});
  EXPECT_EQ(connection.queryInt64("SELECT count(*) FROM api_tokens"), 0);

  // A first start whose token file is its new database: refused before the database is made.
  const std::string fresh = dir.file("fresh.db");
  const CommandResult serve =
      RunPintag("serve --port 0 --bind 127.0.0.1 --db " + fresh + " --admin-token-out " + fresh);
  EXPECT_EQ(serve.status, 2) << serve.out;
  EXPECT_NE(serve.out.find("--admin-token-out " + fresh + " is the database"), std::string::npos)
      << serve.out;
  EXPECT_FALSE(std::filesystem::exists(fresh));
}

// An empty file name (an unset shell variable) or one SQLite reads as a database in memory
// reported success for writes that were thrown away.
TEST(CliWrites, AnEmptyOrInMemoryDatabaseNameIsRefused) {
  const TempDir dir;
  for (const std::string db : {"''", ":memory:", "'file:x?mode=memory'"}) {
    for (const std::string& command :
         {"token create --role admin --db " + db, "keys lookup 110001 --db " + db,
          "snapshot --out " + dir.file("s") + " --db " + db}) {
      // Run in `dir`, so that a name taken as a file's would show there.
      const CommandResult refused =
          RunShell("cd " + dir.path().string() + " && " + PintagExe() + " " + command + " 2>&1");
      EXPECT_EQ(refused.status, 2) << command << "\n" << refused.out;
      EXPECT_NE(refused.out.find("--db: "), std::string::npos) << refused.out;
    }
  }
  const CommandResult empty_out =
      RunPintag("token create --role admin --out '' --db " + dir.file("t.db"));
  EXPECT_EQ(empty_out.status, 2) << empty_out.out;
  EXPECT_NE(empty_out.out.find("--out: needs a file name"), std::string::npos) << empty_out.out;
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

// Another process holding the write lock (an import) for longer than the busy timeout: the token
// commands say so and what they left undone, where they printed SQLite's "database is locked".
TEST(CliWrites, TokenCommandsSayTheDatabaseIsBusyAndWhatTheyLeftUndone) {
  const TempDir dir;
  const std::string db = dir.file("copy.db");
  std::filesystem::copy_file(SeededTemplate(), db);
  const CommandResult made = RunPintag("token create --role counter --db " + db);
  ASSERT_EQ(made.status, 0) << made.out;
  const std::string id = made.out.substr(6, made.out.find(' ', 6) - 6);  // "token N (counter)…"
  HeldWriteLock lock(db);
  const CommandResult create = RunPintag("token create --role admin --db " + db);
  EXPECT_EQ(create.status, 1) << create.out;
  EXPECT_NE(create.out.find(db + " is being written by another process"), std::string::npos)
      << create.out;
  EXPECT_NE(create.out.find("no token was made"), std::string::npos) << create.out;
  const CommandResult revoke = RunPintag("token revoke " + id + " --db " + db);
  EXPECT_EQ(revoke.status, 1) << revoke.out;
  EXPECT_NE(revoke.out.find("the token was not revoked"), std::string::npos) << revoke.out;
  lock.release();
  EXPECT_EQ(RunPintag("token revoke " + id + " --db " + db).status, 0) << id;
}

// The first start of `pintag serve` prints the first admin token. Printed nowhere, it stayed
// working, and later starts print none (the table is no longer empty): the only admin secret was
// lost while the server served on, exit 0 at its stop.
TEST(CliWrites, AServerWhoseFirstAdminTokenCannotBePrintedRevokesItAndDoesNotStart) {
  ASSERT_TRUE(std::filesystem::exists(kFull)) << "the full disk these tests write to";
  const TempDir dir;
  const std::string db = dir.file("copy.db");
  std::filesystem::copy_file(SeededTemplate(), db);
  // Bounded: a server that starts regardless would serve until stopped.
  const CommandResult run =
      RunShell("timeout 60 " + PintagExe() + " serve --port 0 --bind 127.0.0.1 --db " + db +
               " 2>&1 >" + kFull);
  EXPECT_EQ(run.status, 1) << run.out;
  EXPECT_NE(run.out.find("the token is revoked; make an admin token with `pintag token create "
                         "--role admin --db " +
                         db + "`"),
            std::string::npos)
      << run.out;
  ExpectOneAdminTokenRevoked(dir, db);
}

/// How a command ended whose stdout was a pipe with no reader left, and what it wrote to stderr.
struct PipeRun {
  int status = 0;  // the exit status, or -1 when a signal ended the command
  std::string err;
};

/// Runs `pintag` with `words` and its stdout a pipe whose reader has gone (`... | head -c0`), with
/// SIGPIPE at its default in the command, whatever this process does with it.
PipeRun RunPintagIntoAClosedPipe(const TempDir& dir, const std::vector<std::string>& words) {
  int pipe_fds[2];
  EXPECT_EQ(::pipe2(pipe_fds, O_CLOEXEC), 0);
  ::close(pipe_fds[0]);
  const std::string err = dir.file("err.txt");
  const pid_t pid = SpawnPintagWith(words, pipe_fds[1], STDOUT_FILENO, err);
  ::close(pipe_fds[1]);
  EXPECT_GT(pid, 0);
  if (pid <= 0) return {};
  int status = 0;
  EXPECT_EQ(::waitpid(pid, &status, 0), pid);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, ReadFile(err)};
}

// The same through a pipe whose reader has gone (`pintag token create | head -c0`): SIGPIPE
// killed the command before it could revoke the token it had made.
TEST(CliWrites, ATokenWrittenToAClosedPipeIsRevoked) {
  const TempDir dir;
  const std::string db = dir.file("copy.db");
  std::filesystem::copy_file(SeededTemplate(), db);
  const PipeRun run =
      RunPintagIntoAClosedPipe(dir, {"token", "create", "--role", "admin", "--db", db});
  EXPECT_EQ(run.status, 1) << run.err;
  EXPECT_NE(run.err.find("the token is revoked"), std::string::npos) << run.err;
  ExpectOneAdminTokenRevoked(dir, db);
}

// A reader that stops early (`pintag keys export | head -1`) made the command say "cannot write
// ... to standard output" and exit 1, which `set -o pipefail` scripts took for a failure. Like
// `seq 100000 | head -1`, it now ends quietly with the status SIGPIPE gives (141); a full disk is
// still an error (below).
TEST(CliWrites, AReaderThatStopsReadingIsNotAnError) {
  const TempDir dir;
  const std::string db = dir.file("copy.db");
  std::filesystem::copy_file(SeededTemplate(), db);
  for (const std::vector<std::string>& words :
       {std::vector<std::string>{"keys", "export", "--db", db},
        std::vector<std::string>{"keys", "lookup", "110001", "--db", db},
        std::vector<std::string>{"token", "list", "--db", db},
        std::vector<std::string>{"--help"}}) {
    const PipeRun run = RunPintagIntoAClosedPipe(dir, words);
    EXPECT_EQ(run.status, 141) << words[0] << " " << words[1] << ": " << run.err;
    EXPECT_EQ(run.err, "") << words[0] << " " << words[1];
  }
}

TEST(CliWrites, DetectImagesToAFullDiskFail) {
  // Small images: OpenCV's writers buffer all of one and never check the close, so cv::imwrite
  // said true, and the debug images' writes were not checked at all.
  ASSERT_TRUE(std::filesystem::exists(kFull)) << "the full disk these tests write to";
  const TempDir dir;
  const std::string blank = dir.file("blank.png");
  ASSERT_TRUE(cv::imwrite(blank, cv::Mat(16, 16, CV_8UC3, cv::Scalar(200, 200, 200))));
  const std::string overlay = dir.file("seen.png");
  std::filesystem::create_symlink(kFull, overlay);
  const CommandResult drawn = RunPintag("detect " + blank + " --overlay " + overlay);
  EXPECT_EQ(drawn.status, 1) << drawn.out;
  EXPECT_NE(drawn.out.find("cannot write overlay"), std::string::npos) << drawn.out;

  const std::string photo = dir.file("tag.png");
  ASSERT_EQ(RunPintag("render --key 11684 --size-px 64 -o " + photo).status, 0);
  const std::filesystem::path debug = dir.path() / "stages";
  std::filesystem::create_directory(debug);
  std::filesystem::create_symlink(kFull, debug / "1_redness.png");
  const CommandResult staged = RunPintag("detect " + photo + " --debug-dir " + debug.string());
  EXPECT_EQ(staged.status, 1) << staged.out;
  EXPECT_NE(staged.out.find("cannot write debug image"), std::string::npos) << staged.out;
  EXPECT_NE(staged.out.find("1_redness.png"), std::string::npos) << staged.out;
  // The stages after the one that failed are still written.
  EXPECT_TRUE(std::filesystem::is_regular_file(debug / "4_detections.png"));
}

TEST(CliWrites, AnyCommandWhoseOutputIsLostExitsOne) {
  ASSERT_TRUE(std::filesystem::exists(kFull)) << "the full disk these tests write to";
  const TempDir dir;
  const std::string db = dir.file("copy.db");
  std::filesystem::copy_file(SeededTemplate(), db);
  for (const std::string& command :
       {"keys lookup 110001 --db " + db, "token list --db " + db, std::string("--help")}) {
    const CommandResult run = RunPintagWithStdoutTo(command, kFull);
    EXPECT_EQ(run.status, 1) << command << ": " << run.out;
    EXPECT_NE(run.out.find("cannot write to standard output"), std::string::npos)
        << command << ": " << run.out;
  }
  const CommandResult fine = RunPintagWithStdoutTo("keys lookup 110001 --db " + db, "/dev/null");
  EXPECT_EQ(fine.status, 0) << fine.out;

  // An import whose summary is lost is still committed, and says so: a bare "cannot write to
  // standard output" read as if it had failed.
  const std::string csv = WriteFile(
      dir.file("one.csv"),
      "circlename,regionname,divisionname,officename,pincode,officetype,delivery,district,"
      "statename,latitude,longitude\n"
      "Delhi,Delhi,New Delhi,Somewhere,999871,BO,Delivery,Central Delhi,Delhi,NA,NA\n");
  const CommandResult imported = RunPintagWithStdoutTo("import " + csv + " --db " + db, kFull);
  EXPECT_EQ(imported.status, 1) << imported.out;
  EXPECT_NE(imported.out.find("cannot write the summary to standard output; the import of " + csv +
                              " into " + db + " is committed"),
            std::string::npos)
      << imported.out;
  EXPECT_EQ(RunPintag("keys lookup 999871 --db " + db).status, 0);
}

}  // namespace
}  // namespace pintag::serve_test
