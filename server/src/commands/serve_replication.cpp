#include "commands/serve_replication.hpp"

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <thread>

#include "commands/commands.hpp"
#include "commands/option_checks.hpp"
#include "pintag/db/scan_log.hpp"
#include "pintag/db/snapshot.hpp"
#include "pintag/db/tokens.hpp"
#include "pintag/server/log.hpp"
#include "replica/token_file.hpp"

namespace pintag::cli {
namespace {

std::string Beside(const std::string& path, const std::string& suffix) {
  const std::filesystem::path p(path);
  return (p.parent_path() / (p.stem().string() + suffix)).string();
}

std::string ReadToken(const ReplicationArgs& args) {
  std::string token;
  if (!args.follow_token_file.empty()) {
    const std::optional<std::string> read = replica::ReadTokenFile(args.follow_token_file);
    if (!read) {
      // Said with why: a file that cannot be opened, or one whose first line holds no token
      // (which was told to "set PINTAG_FOLLOW_TOKEN or give --follow-token-file", given).
      errno = 0;
      std::error_code error;
      if (std::filesystem::is_directory(args.follow_token_file, error)) {
        throw UsageError("--follow-token-file " + args.follow_token_file + " is a directory");
      }
      if (!std::ifstream(args.follow_token_file)) {
        const int why = errno;
        throw UsageError("cannot read --follow-token-file " + args.follow_token_file +
                         (why != 0 ? std::string(": ") + std::strerror(why) : std::string()));
      }
      throw UsageError("--follow-token-file " + args.follow_token_file +
                       " holds no token (its first line is empty); write one there on the "
                       "primary: pintag token create --role replica --out FILE");
    }
    token = *read;
  } else if (const char* env = std::getenv("PINTAG_FOLLOW_TOKEN")) {
    token = env;
  }
  while (!token.empty() && (token.back() == '\r' || token.back() == ' ')) token.pop_back();
  if (token.empty()) {
    throw UsageError(
        "--follow needs a replica token: set PINTAG_FOLLOW_TOKEN or give "
        "--follow-token-file (make one on the primary: pintag token create --role "
        "replica)");
  }
  // A typo, or a secret cut short by a copy, is said now: it was the primary's 401 at every poll.
  if (!db::HasTokenForm(token)) {
    throw UsageError(
        std::string("the replica token ") +
        (args.follow_token_file.empty() ? "in PINTAG_FOLLOW_TOKEN"
                                        : "in --follow-token-file " + args.follow_token_file) +
        " is not a PinTag token's secret (pt_, its id, _ and 43 characters); make one on the "
        "primary: pintag token create --role replica");
  }
  return token;
}

std::string WithoutTrailingSlashes(std::string url) {
  while (!url.empty() && url.back() == '/') url.pop_back();
  return url;
}

/// The primary's base URL as given to --follow, without the trailing slash the server's own
/// banner prints ("http://host:8090/"). Anything but scheme://host[:port], the port 1-65535, is
/// a usage error: the snapshot route is asked for at the root, and cpp-httplib's client throws on
/// a port beyond an int and polls nothing for a host it cannot parse.
std::string PrimaryBaseUrl(std::string url) {
  url = WithoutTrailingSlashes(std::move(url));
  const auto refuse = [&] {
    return UsageError(
        "--follow takes the primary's base URL, http://HOST[:PORT] or "
        "https://HOST[:PORT] with no path; got \"" +
        url + "\"");
  };
  const std::size_t scheme_end = url.find("://");
  if (scheme_end == std::string::npos) throw refuse();
  const std::string scheme = url.substr(0, scheme_end);
  const std::string authority = url.substr(scheme_end + 3);
  // [v6 address]:port, or host:port; the host is letters, digits, '.', '-', '_'.
  std::string host = authority;
  std::string port;
  if (!authority.empty() && authority.front() == '[') {
    const std::size_t close = authority.find(']');
    if (close == std::string::npos) throw refuse();
    host = authority.substr(1, close - 1);
    const std::string rest = authority.substr(close + 1);
    if (!rest.empty() && rest.front() != ':') throw refuse();
    if (!rest.empty()) port = rest.substr(1);
    // cpp-httplib 0.11 reads an IPv6 literal of digits and colons only.
    if (host.empty() || host.find_first_not_of("0123456789:") != std::string::npos) {
      throw refuse();
    }
  } else {
    const std::size_t colon = authority.find(':');
    if (colon != std::string::npos) {
      host = authority.substr(0, colon);
      port = authority.substr(colon + 1);
      if (port.empty()) throw refuse();
    }
    if (host.empty() ||
        host.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                               "0123456789.-_") != std::string::npos) {
      throw refuse();
    }
  }
  const bool port_ok = port.empty() || (port.size() <= 5 &&
                                        port.find_first_not_of("0123456789") == std::string::npos &&
                                        std::stoi(port) >= 1 && std::stoi(port) <= 65535);
  if ((scheme != "http" && scheme != "https") || !port_ok) throw refuse();
  return url;
}

}  // namespace

void CheckReplicationArgs(const ReplicationArgs& args, const std::string& db_path) {
  const bool replica = args.read_only || !args.follow.empty();
  if (!replica) {
    // Each was taken without a word and did nothing: a primary keeps its scan log in --db and
    // follows no one.
    for (const auto& [given, name] :
         {std::pair{!args.scan_log.empty(), "--scan-log"},
          std::pair{!args.primary.empty(), "--primary"},
          std::pair{!args.follow_token_file.empty(), "--follow-token-file"},
          std::pair{args.follow_interval_ms.has_value(), "--follow-interval-ms"}}) {
      if (given) {
        throw UsageError(
            std::string(name) +
            " is for a replica (--read-only or --follow); a primary has no use for it");
      }
    }
  }
  // The token is read from the environment by ReadToken, not by CLI11, so it is checked here as
  // --follow-token-file is: a secret set where nothing follows was silently unused.
  if (const char* token = std::getenv("PINTAG_FOLLOW_TOKEN");
      token != nullptr && *token != '\0' && args.follow.empty()) {
    throw UsageError(
        std::string("the environment variable PINTAG_FOLLOW_TOKEN is a replica's token "
                    "for --follow; ") +
        (replica ? "this replica follows no one" : "a primary has no use for it") +
        ": unset it here");
  }
  if (replica && args.follow.empty()) {
    if (!args.follow_token_file.empty()) {
      throw UsageError(
          "--follow-token-file is the token for --follow; this replica follows no one");
    }
    if (args.follow_interval_ms) {
      throw UsageError(
          "--follow-interval-ms is how often --follow asks; this replica follows no one");
    }
  }
  if (replica && !args.snapshot.empty()) {
    throw UsageError("--snapshot publishes a primary's registry; a --read-only replica has none");
  }
  if (replica && !args.scan_log.empty()) {
    // A follower's --db may not be there yet, so the scan log's own check (other tables) cannot
    // see it: made as a scan log, it would refuse every snapshot after.
    std::error_code log_error;
    std::error_code db_error;
    std::error_code same_error;
    const std::filesystem::path log = std::filesystem::weakly_canonical(args.scan_log, log_error);
    const std::filesystem::path db = std::filesystem::weakly_canonical(db_path, db_error);
    if ((!log_error && !db_error && log == db) ||
        std::filesystem::equivalent(args.scan_log, db_path, same_error)) {
      throw UsageError("--scan-log " + args.scan_log + " is the replica's --db " + db_path +
                       ", which every snapshot replaces; give the scan log a file of its own");
    }
  }
  if (!args.snapshot.empty()) {
    std::error_code error;
    // Before the database is created and seeded: a mistyped directory leaves nothing behind.
    const std::filesystem::path snapshot_dir =
        std::filesystem::absolute(args.snapshot).parent_path();
    if (!std::filesystem::is_directory(snapshot_dir, error)) {
      throw UsageError("--snapshot " + args.snapshot + ": its directory " + snapshot_dir.string() +
                       (error && error != std::errc::no_such_file_or_directory
                            ? " cannot be looked at: " + error.message()
                            : " does not exist"));
    }
    // A pipe, socket or device at the path is never a snapshot file: said now, where the server
    // started and then logged a failed publication every second. What can be put right while
    // the primary serves (a directory at the path removed, the directory made writable, a disk
    // freed) stays a failed publication, logged and tried again: a primary serves without one.
    if (const FileToReplace target = FileReplacedBy(args.snapshot);
        !target.problem.empty() && !std::filesystem::is_directory(target.path, error)) {
      throw UsageError("--snapshot " + target.problem);
    }
    const std::filesystem::path snapshot = std::filesystem::weakly_canonical(args.snapshot, error);
    const std::filesystem::path db = std::filesystem::weakly_canonical(db_path, error);
    const bool same = snapshot == db || std::filesystem::equivalent(args.snapshot, db_path, error);
    const bool its_file = !db::DatabaseOwningFile(snapshot.string(), db.string()).empty();
    if (same || its_file) {
      throw UsageError("--snapshot " + args.snapshot + " would replace the database " + db_path +
                       (same ? "" : " or one of its files") + "; publish it to another path");
    }
  }
}

void AddReplicationOptions(CLI::App* serve, ReplicationArgs& args) {
  serve
      ->add_flag("--read-only", args.read_only,
                 "serve --db as a read-only snapshot (a replica): writes answer 403 naming the "
                 "primary; a newer snapshot renamed into place, or SIGHUP, reloads it")
      ->envname("PINTAG_READ_ONLY");
  serve
      ->add_option("--follow", args.follow,
                   "pull newer snapshots from this primary URL (implies --read-only; token in "
                   "PINTAG_FOLLOW_TOKEN or --follow-token-file)")
      ->envname("PINTAG_FOLLOW");
  serve
      ->add_option("--follow-token-file", args.follow_token_file,
                   "file holding the replica token for --follow")
      ->check(FileName())
      ->envname("PINTAG_FOLLOW_TOKEN_FILE");
  serve
      ->add_option("--follow-interval-ms", args.follow_interval_ms,
                   "how often to ask the primary for a newer snapshot (default 1000)")
      ->check(CLI::Range(50, 3'600'000))
      ->envname("PINTAG_FOLLOW_INTERVAL_MS");
  serve
      ->add_option("--primary", args.primary,
                   "the primary's URL, named when a replica refuses a write (default: --follow)")
      ->envname("PINTAG_PRIMARY");
  serve
      ->add_option("--scan-log", args.scan_log,
                   "a replica's own scan log file (default: <db name>-scans.db beside --db)")
      ->check(DatabaseFileName())
      ->envname("PINTAG_SCAN_LOG");
  serve
      ->add_option("--snapshot", args.snapshot,
                   "publish registry snapshots for replicas to this file, after every change "
                   "(GET /api/v1/registry/snapshot)")
      ->check(FileName())
      ->envname("PINTAG_SNAPSHOT");
}

Replication::Replication(const ReplicationArgs& args, app::AppConfig& config)
    : args_(args), db_path_(config.db_path) {
  if (!args_.follow.empty()) {
    args_.follow = PrimaryBaseUrl(args_.follow);
    args_.read_only = true;
  }
  // Only a name in refusals: a primary behind a path prefix may be named so.
  args_.primary = WithoutTrailingSlashes(args_.primary);
  if (args_.read_only && !args_.snapshot.empty()) {
    throw UsageError("--snapshot publishes a primary's registry; a --read-only replica has none");
  }
  if (!args_.read_only) {
    if (args_.snapshot.empty()) return;
    // A failed write (a full disk, a file another process holds) is not a reason to keep the
    // only writer down: it is logged, tried again with backoff, and shown by GET
    // /api/v1/registry and the metrics until it works. (A directory that is not there is a
    // mistake in the command: CheckReplicationArgs refused it before the database was made.)
    publisher_ = std::make_shared<replica::SnapshotPublisher>(db_path_, args_.snapshot);
    if (!publisher_->publish()) {
      server::LogEvent(
          "starting without a published snapshot; replicas are answered 503 until one is written",
          /*warning=*/true);
    }
    config.publisher = publisher_;
    return;
  }

  // A replica's --db is replaced by every snapshot: never a registry a server writes (the
  // primary's own file, when both run with the default --db in one directory).
  if (const std::string live = db::LiveDatabaseAt(db_path_); !live.empty()) {
    throw std::runtime_error(live + ": a read-only replica serves a snapshot of its own; give it " +
                             "another --db (a --follow replica fetches one there)");
  }
  if (args_.follow.empty() && !std::filesystem::exists(db_path_)) {
    throw std::runtime_error("--read-only serves a registry snapshot, and " + db_path_ +
                             " does not exist: make one on the primary with `pintag snapshot "
                             "--db FILE --out " +
                             db_path_ + "`, or give --follow URL to fetch one");
  }
  // The token first: a start refused for it leaves no scan log file made.
  if (!args_.follow.empty()) token_ = ReadToken(args_);
  // Before a follower waits for its first snapshot: a --scan-log given by mistake (another
  // replica's snapshot) is refused at once, not once the primary is up.
  const std::string scan_log =
      args_.scan_log.empty() ? Beside(db_path_, "-scans.db") : args_.scan_log;
  if (auto opened = db::OpenScanLogFile(scan_log); !opened) {
    throw std::runtime_error("scan log " + scan_log + ": " + opened.error().message);
  }
  if (!args_.follow.empty()) {
    follow_status_ = std::make_shared<replica::FollowStatus>();
    config.follow_status = follow_status_;
    // One follower from the first fetch on: it keeps the ETag of what it installed, so its first
    // poll is a 304, not the whole snapshot again.
    follower_ = std::make_unique<replica::SnapshotFollower>(
        replica::FollowOptions{.primary_url = args_.follow,
                               .token = token_,
                               .token_file = args_.follow_token_file,
                               .path = db_path_},
        [this](const db::SnapshotInfo&) { watcher_->check(); });
    // A replica with no usable snapshot yet waits for its primary.
    if (!db::VerifySnapshot(db_path_)) {
      std::string last_error;
      while (true) {
        const auto fetched = follower_->fetch(std::nullopt);
        if (fetched && *fetched) break;
        const std::string error = fetched ? "no snapshot" : fetched.error().message;
        if (error != last_error) {
          server::LogEvent("waiting for a snapshot from " + args_.follow + ": " + error,
                           /*warning=*/true);
        }
        last_error = error;
        std::this_thread::sleep_for(std::chrono::milliseconds(args_.followIntervalMs()));
      }
    }
  }
  watcher_ = std::make_unique<replica::SnapshotWatcher>(
      db_path_, [this](const db::SnapshotInfo& loaded) { pool_->renew(loaded.path); });

  pool_ =
      std::make_shared<app::ConnectionPool>(watcher_->loaded().path, config.busy_timeout_ms, true);
  config.read_only = true;
  config.pool = pool_;
  config.scan_log_path = scan_log;
  // The watcher outlives the server: this Replication is made before it and ends after it.
  config.served_file_health = [watcher = watcher_.get()] { return watcher->servedDamage(); };
  config.primary_url = !args_.primary.empty() ? args_.primary : args_.follow;  // or unknown
}

Replication::~Replication() {
  // Threads stop before what they call into goes away.
  follower_.reset();
  watcher_.reset();
  publisher_.reset();
}

void Replication::start() {
  if (publisher_) publisher_->start(std::chrono::milliseconds(500));
  if (!args_.read_only) return;
  watcher_->start(std::chrono::milliseconds(250));
  if (!follower_) return;
  follower_->start([watcher = watcher_.get()] { return watcher->servedVersion(); },
                   std::chrono::milliseconds(args_.followIntervalMs()), follow_status_);
}

void Replication::reload() {
  if (!watcher_ && !follower_) {
    server::LogEvent("SIGHUP: nothing to reload (a primary reads its database as it changes)");
    return;
  }
  // Said whatever it finds, so that an operator who sent it sees it arrived (a new file is
  // logged by the watcher as it is taken).
  std::string done;
  if (watcher_ && !watcher_->check()) {
    const std::optional<std::string> damage = watcher_->servedDamage();
    done = "no new snapshot taken from " + db_path_ +
           (damage ? " (not ready: " + *damage + ")"
                   : " (serving registry version " +
                         std::to_string(watcher_->loaded().registry_version) + ")");
  }
  if (follower_) {
    // A rotated replica token: written to --follow-token-file, then SIGHUP.
    try {
      const bool changed = follower_->setToken(ReadToken(args_));
      const std::string source =
          args_.follow_token_file.empty() ? "PINTAG_FOLLOW_TOKEN" : args_.follow_token_file;
      if (!done.empty()) done += "; ";
      done += changed ? "took a new replica token from " + source + " for the next poll"
                      : "the replica token in " + source + " is the one in use";
    } catch (const std::exception& e) {
      server::LogEvent(std::string("SIGHUP: keeping the replica token: ") + e.what(),
                       /*warning=*/true);
    }
  }
  if (!done.empty()) server::LogEvent("SIGHUP: " + done);
}

std::string Replication::describe() const {
  if (publisher_) return "primary, publishing snapshots to " + args_.snapshot;
  if (!args_.read_only) return "";
  std::string text = "read-only replica at registry version " +
                     std::to_string(watcher_->loaded().registry_version);
  if (!args_.follow.empty()) text += ", following " + args_.follow;
  return text;
}

}  // namespace pintag::cli
