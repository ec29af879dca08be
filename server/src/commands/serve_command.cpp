// `pintag serve`: the HTTP API over one database. On first start with no database file it creates
// and seeds one; when the token table is empty it creates one admin token and prints its secret
// on stdout, the only place it ever appears. SIGINT or SIGTERM stops it gracefully (in-flight
// requests finish).

#include <malloc.h>
#include <signal.h>
#include <sys/resource.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <opencv2/core/utility.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "app/app.hpp"
#include "commands/commands.hpp"
#include "commands/open_db.hpp"
#include "commands/option_checks.hpp"
#include "commands/serve_replication.hpp"
#include "commands/serve_signals.hpp"
#include "commands/unseen_token.hpp"
#include "pintag/db/database.hpp"
#include "pintag/db/tokens.hpp"
#include "pintag/server/http_server.hpp"
#include "pintag/server/listen_check.hpp"
#include "pintag/server/log.hpp"
#include "pintag/server/trusted_proxies.hpp"

namespace pintag::cli {
namespace {

struct ServeArgs {
  std::string db = "pintag.db";
  int port = 8080;
  std::string bind = "127.0.0.1";
  int threads = 4;
  std::string web;
  std::string admin_token_out;
  double max_body_mb = 25;
  std::int64_t max_pixels = 40'000'000;
  std::optional<std::int64_t> max_pixels_in_flight;  // none: twice max_pixels
  int max_batch = 100;
  int max_tag_px = 4096;
  int read_timeout_s = 5;
  int write_timeout_s = 5;
  std::int64_t min_body_rate = 500;
  int drain_timeout_s = 30;
  std::string log_format = "text";
  std::vector<std::string> trusted_proxies;
  ReplicationArgs replication;
};

/// Followed by the database's path and a closing backquote.
constexpr const char* kMakeAdminToken = "`pintag token create --role admin --db ";

/// On an empty token table, creates the first admin token and returns it; nothing when tokens
/// already exist. Called once the port is bound, so a start that cannot listen does not create a
/// token nobody sees.
std::optional<db::NewToken> FirstAdminToken(const std::string& path) {
  auto opened = db::OpenDatabase(path, {.create = false});
  if (!opened) throw std::runtime_error(opened.error().message);
  db::Connection& connection = opened.value().connection;
  auto tokens = db::ListTokens(connection);
  if (!tokens) throw std::runtime_error(tokens.error().message);
  if (!tokens->empty()) return std::nullopt;
  auto token = db::CreateToken(connection, db::Role::kAdmin, "first start of pintag serve");
  if (!token) throw std::runtime_error(token.error().message);
  return std::move(token).value();
}

/// glibc gives each busy thread its own malloc arena, up to 8 per core; the detector's
/// megabyte buffers then fragment each arena apart. Measured with the soak (64 threads, mixed
/// load, docs/RELIABILITY.md): resident memory grew 19.6 % over 60 s after warm-up with glibc's
/// default, 2.1 % over 40 s with 2 arenas, at higher throughput. MALLOC_ARENA_MAX still wins.
void LimitMallocArenas() {
  if (std::getenv("MALLOC_ARENA_MAX") == nullptr) mallopt(M_ARENA_MAX, 2);
}

/// Requests run in parallel on the worker threads, one each; OpenCV's own thread pool (TBB) would
/// split a request's resizes and thresholds across threads that are busy with other requests, and
/// its idle workers spin in sched_yield (1 % of the server's CPU under detect load, perf).
void OneOpenCvThreadPerRequest() {
  cv::setNumThreads(1);
}

/// Each waiting connection is an open file (up to 1,024 of them, ServerOptions), beside the
/// databases and photos the workers open. A soft limit of 1,024, systemd's default, ran out before
/// waiting connections were closed for new ones; the hard limit is the administrator's bound.
void RaiseOpenFileLimit() {
  rlimit limit{};
  if (::getrlimit(RLIMIT_NOFILE, &limit) == 0 && limit.rlim_cur < limit.rlim_max) {
    limit.rlim_cur = limit.rlim_max;
    ::setrlimit(RLIMIT_NOFILE, &limit);
  }
}

void Run(const ServeArgs& args) {
  // SIGHUP asks a replica to reload; a follower may wait long for its first snapshot below, and
  // SIGHUP's default action would end it there. Handled now, a SIGHUP waits until the signal
  // thread takes it as a reload. SIGINT and SIGTERM still stop the process while it waits.
  ServeSignals signals;
  LimitMallocArenas();
  OneOpenCvThreadPerRequest();
  RaiseOpenFileLimit();
  server::ConfigureLog(server::ParseLogFormat(args.log_format).value_or(server::LogFormat::kText));
  // An empty address would listen on every interface unasked.
  if (args.bind.empty()) throw UsageError("--bind needs an address, e.g. 127.0.0.1 or 0.0.0.0");
  if (!args.web.empty() && !std::filesystem::is_directory(args.web)) {
    throw UsageError("--web " + args.web + " is not a directory");
  }
  // A mistyped path, or a directory this user cannot write (a volume owned by root while the
  // server runs as another user), is said now, before the database and the token are made.
  if (!args.admin_token_out.empty()) {
    CheckSecretFile("--admin-token-out", args.admin_token_out, args.db);
  }
  std::string proxy_error;
  const std::optional<server::TrustedProxies> trusted_proxies =
      server::TrustedProxies::Parse(args.trusted_proxies, &proxy_error);
  if (!trusted_proxies) throw UsageError("--trusted-proxy " + proxy_error);
  // Two photos of the largest size at once by default: with a 40 MP limit, photos and PNGs in
  // flight hold about 0.6 GB at most, however many threads serve.
  const std::int64_t max_pixels_in_flight = args.max_pixels_in_flight.value_or(2 * args.max_pixels);
  if (max_pixels_in_flight < args.max_pixels) {
    throw UsageError("--max-pixels-in-flight " + std::to_string(max_pixels_in_flight) +
                     " is below --max-pixels " + std::to_string(args.max_pixels) +
                     ": it must hold at least one photo of the largest size allowed");
  }
  // A port taken (a second start by mistake) is said before a missing database is created and
  // seeded, which takes seconds; bind() below still decides.
  if (args.port != 0) {
    if (const std::string why = server::WhyCannotListen(args.bind, args.port); !why.empty()) {
      throw std::runtime_error("cannot listen on " + args.bind + ":" + std::to_string(args.port) +
                               ": " + why);
    }
  }
  CheckReplicationArgs(args.replication, args.db);
  const bool read_only = args.replication.read_only || !args.replication.follow.empty();
  if (!read_only) {
    // Creates and seeds a missing file, migrates an old one; says so in the server's log.
    OpenDb(args.db, [](const std::string& what) { server::LogEvent(what); });
  }

  app::AppConfig config;
  config.db_path = args.db;
  Replication replication(args.replication, config);
  // A primary's pool is made here so that a forced stop can still empty the log of a database
  // file moved away under the server (app/connection_pool.hpp).
  std::shared_ptr<app::ConnectionPool> writable_pool;
  if (!read_only) {
    writable_pool = std::make_shared<app::ConnectionPool>(args.db, config.busy_timeout_ms);
    config.pool = writable_pool;
  }
  if (!args.web.empty()) config.web_dir = args.web;
  config.max_body_bytes = static_cast<std::size_t>(args.max_body_mb * 1024 * 1024);
  config.max_pixels = args.max_pixels;
  config.max_pixels_in_flight = max_pixels_in_flight;
  config.max_batch = static_cast<std::size_t>(args.max_batch);
  config.max_tag_px = args.max_tag_px;
  config.worker_threads = args.threads;
  server::ServerOptions options;
  options.bind_address = args.bind;
  options.port = args.port;
  options.threads = args.threads;
  options.read_timeout = std::chrono::seconds(args.read_timeout_s);
  options.write_timeout = std::chrono::seconds(args.write_timeout_s);
  options.min_body_rate = static_cast<std::uint64_t>(args.min_body_rate);
  options.trusted_proxies = *trusted_proxies;

  // From here SIGINT and SIGTERM stop the server gracefully; blocked before any thread starts, so
  // that every worker thread inherits the mask and only the waiter below is interrupted.
  signals.takeStopSignals();

  const app::App application = app::BuildApp(config);
  server::HttpServer http(application.api, options);
  std::string error;
  if (!http.bind(&error)) throw std::runtime_error(error);
  const std::optional<db::NewToken> first_admin =
      read_only ? std::nullopt : FirstAdminToken(args.db);
  replication.start();

  const bool any = args.bind == "0.0.0.0" || args.bind == "::";
  // An IPv6 address goes in brackets in a URL, its zone's % as %25 (RFC 3986, RFC 6874):
  // http://[::1]:8080/. Every-interface binds print 127.0.0.1, which answers where IPv6 is off.
  const auto in_url = [](const std::string& address) {
    if (address.find(':') == std::string::npos || address.front() == '[') return address;
    std::string bracketed = "[";
    for (const char c : address) bracketed += c == '%' ? std::string("%25") : std::string(1, c);
    return bracketed + "]";
  };
  const std::string host = any ? "127.0.0.1" : in_url(args.bind);
  const std::string url = "http://" + host + ":" + std::to_string(http.port());
  std::cout << "PinTag serving " << url << "/ (database " << args.db << ", " << args.threads
            << " threads" << (any ? ", all interfaces" : "") << ")\n";
  if (const std::string role = replication.describe(); !role.empty())
    std::cout << "  " << role << "\n";
  // A URL that answers: the API's prefix alone is no route (a reviewer opened it and got 404).
  std::cout << "  a lookup: " << url << "/api/v1/pincodes/110001   OpenAPI: " << url
            << "/openapi.json   health: " << url << "/readyz\n";
  if (first_admin && !args.admin_token_out.empty()) {
    // A container's stdout is kept in its log, where a working secret must not sit.
    db::Connection connection(args.db, {.create = false});
    try {
      RevokeIfUnwritten(connection, first_admin->info.id, args.admin_token_out,
                        WriteSecretFile(args.admin_token_out, first_admin->secret));
    } catch (const std::exception& e) {
      throw std::runtime_error(std::string(e.what()) + "; make an admin token with " +
                               kMakeAdminToken + args.db + "`");
    }
    std::cout << "First start: an admin token was created. Its secret is in "
              << args.admin_token_out
              << " (mode 0600) and shown nowhere else; once you have made your own admin "
                 "tokens, revoke it.\n";
  } else if (first_admin) {
    std::cout << "First start: an admin token was created. Its secret is shown only now (the "
                 "database keeps a hash):\n"
              << "  " << first_admin->secret << "\n"
              << "  e.g. curl -H 'Authorization: Bearer " << first_admin->secret << "' " << url
              << "/api/v1/tokens\n";
  } else if (!read_only) {
    std::cout << "Tokens: pintag token create --role admin|counter|scanner|replica --db " << args.db
              << "\n";
  }
  std::cout << "Stop with Ctrl-C.\n" << std::flush;
  if (first_admin && args.admin_token_out.empty()) {
    // A secret nobody saw must not stay working, and a server nobody can administer must not
    // start as if all were well: revoked, and the start fails (stderr says how to make one).
    // (A secret written to --admin-token-out is in its file, whatever became of stdout.)
    db::Connection connection(args.db, {.create = false});
    try {
      RevokeIfStdoutFailed(connection, first_admin->info.id);
    } catch (const std::exception& e) {
      throw std::runtime_error(std::string(e.what()) + "; make an admin token with " +
                               kMakeAdminToken + args.db + "`");
    }
  }

  std::atomic<bool> finished{false};
  const std::chrono::seconds drain_timeout(args.drain_timeout_s);
  // Cut short, requests in flight get no answer and destructors do not run: what a moved
  // database's log holds is put where it belongs first.
  const auto stop_now = [&finished, writable_pool, scan_log = application.scan_log](int status) {
    if (finished) return;
    if (writable_pool) writable_pool->servesFileAtPath();
    if (const std::size_t held = scan_log->backlog(); held > 0) {
      server::LogEvent("scan log: up to " + std::to_string(held) +
                           " answered scans held back for it are lost (the stop was forced)",
                       /*warning=*/true);
    }
    std::_Exit(status);
  };
  std::thread waiter([&http, &finished, &replication, &signals, drain_timeout, &stop_now] {
    int signal = signals.wait();
    while (signal == SIGHUP && !finished) {
      replication.reload();
      signal = signals.wait();
    }
    if (finished || signal == 0) return;
    const auto name = [](int s) { return std::string(s == SIGINT ? "SIGINT" : "SIGTERM"); };
    server::LogEvent(name(signal) + ", finishing requests in flight (a second signal, or " +
                     std::to_string(drain_timeout.count()) + " s, stops at once)");
    // A signal right after start may come before serve() runs; cpp-httplib ignores stop() then.
    while (!http.running() && !finished) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    http.stop();
    // The drain has a bound: a client sending its upload slowly, or a second Ctrl-C, must not
    // hold the process. Cut short, requests in flight get no answer; what they wrote to the
    // database is committed or not, as after a crash (SQLite's log keeps it whole).
    const auto deadline = std::chrono::steady_clock::now() + drain_timeout;
    for (;;) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      const int next = signals.waitFor(std::max(left, std::chrono::milliseconds(0)));
      if (finished) return;
      if (next == SIGINT || next == SIGTERM) {
        server::LogEvent(name(next) + " again: stopping now, requests in flight are cut off",
                         /*warning=*/true);
        stop_now(128 + next);
        return;
      }
      if (next == -1) {
        server::LogEvent("requests still in flight after " + std::to_string(drain_timeout.count()) +
                             " s (--drain-timeout): stopping now, they are cut off",
                         /*warning=*/true);
        stop_now(1);
        return;
      }
      // SIGHUP while stopping: nothing to reload.
    }
  });
  const bool served = http.serve();
  // serve() returned: stop() ran from the waiter, or serving failed. The scans held back for the
  // scan log are written while the waiter still answers a second signal and the drain's deadline.
  application.scan_log->finish();
  // Then wake the waiter.
  finished = true;
  signals.wake();
  waiter.join();
  http.stop();
  server::LogEvent("stopped");
  if (!served) throw std::runtime_error("the server stopped unexpectedly");
}

void AddServeCommand(CLI::App& app) {
  auto args = std::make_shared<ServeArgs>();
  CLI::App* cmd = app.add_subcommand("serve",
                                     "Serve the HTTP API (labels, detection, registry, "
                                     "routing, tokens)");
  cmd->add_option("--db", args->db, "database file (created and seeded when missing)")
      ->check(DatabaseFileName())
      ->capture_default_str()
      ->envname("PINTAG_DB");
  cmd->add_option("--port", args->port, "TCP port; 0 picks a free one (printed)")
      ->check(CLI::Range(0, 65535))
      ->capture_default_str()
      ->envname("PINTAG_PORT");
  cmd->add_option("--bind", args->bind, "address to listen on; 0.0.0.0 for every interface")
      ->capture_default_str()
      ->envname("PINTAG_BIND");
  cmd->add_option("--threads", args->threads, "worker threads (concurrent requests)")
      ->check(CLI::Range(1, 256))
      ->capture_default_str()
      ->envname("PINTAG_THREADS");
  cmd->add_option("--web", args->web, "serve static files from this directory (default: none)")
      ->envname("PINTAG_WEB");
  cmd->add_option("--admin-token-out", args->admin_token_out,
                  "on a first start, write the first admin token's secret to this file (mode "
                  "0600) instead of stdout, which a container's log keeps")
      ->check(FileName())
      ->envname("PINTAG_ADMIN_TOKEN_OUT");
  cmd->add_option("--max-body-mb", args->max_body_mb, "largest request body, MiB (413 above)")
      ->check(FiniteNumber())
      ->check(CLI::Range(0.001, 1024.0))
      ->capture_default_str()
      ->envname("PINTAG_MAX_BODY_MB");
  cmd->add_option("--max-pixels", args->max_pixels,
                  "largest photo to decode, pixels, checked from its header (413 above)")
      ->check(CLI::Range(std::int64_t{1}, std::int64_t{1'000'000'000}))
      ->capture_default_str()
      ->envname("PINTAG_MAX_PIXELS");
  cmd->add_option("--max-pixels-in-flight", args->max_pixels_in_flight,
                  "pixels of uploaded photos being decoded and detected and of label and tag PNGs "
                  "being rendered, at once over all requests (about 7 bytes of memory each); "
                  "more waits its turn. At least --max-pixels; default twice --max-pixels")
      ->check(CLI::Range(std::int64_t{1}, std::int64_t{100'000'000'000}))
      ->envname("PINTAG_MAX_PIXELS_IN_FLIGHT");
  cmd->add_option("--max-batch", args->max_batch, "labels per POST /api/v1/labels (413 above)")
      ->check(CLI::Range(1, 10000))
      ->capture_default_str()
      ->envname("PINTAG_MAX_BATCH");
  cmd->add_option("--max-tag-px", args->max_tag_px, "largest tag PNG square side, pixels")
      ->check(CLI::Range(64, 16384))
      ->capture_default_str()
      ->envname("PINTAG_MAX_TAG_PX");
  cmd->add_option("--read-timeout", args->read_timeout_s, "seconds per read of a request")
      ->check(CLI::Range(1, 3600))
      ->capture_default_str()
      ->envname("PINTAG_READ_TIMEOUT");
  cmd->add_option("--write-timeout", args->write_timeout_s, "seconds per write of a response")
      ->check(CLI::Range(1, 3600))
      ->capture_default_str()
      ->envname("PINTAG_WRITE_TIMEOUT");
  cmd->add_option("--min-body-rate", args->min_body_rate,
                  "the pace a request body must keep: the server waits for its bytes at most "
                  "four --read-timeout plus a second for every this many bytes; slower is "
                  "answered 408 (0: no minimum)")
      ->check(CLI::Range(std::int64_t{0}, std::int64_t{1'000'000'000}))
      ->capture_default_str()
      ->envname("PINTAG_MIN_BODY_RATE");
  cmd->add_option("--drain-timeout", args->drain_timeout_s,
                  "seconds a stop waits for requests in flight before cutting them off")
      ->check(CLI::Range(1, 3600))
      ->capture_default_str()
      ->envname("PINTAG_DRAIN_TIMEOUT");
  cmd->add_option("--log-format", args->log_format,
                  "server log on stderr: text (key=value lines) or json (one object a line)")
      ->check(CLI::IsMember({"text", "json"}))
      ->envname("PINTAG_LOG_FORMAT")
      ->capture_default_str();
  cmd->add_option("--trusted-proxy", args->trusted_proxies,
                  "a reverse proxy (address, or range such as 10.0.0.0/8; repeat or separate "
                  "with commas) whose X-Forwarded-For names the client in the access log "
                  "(default: none, the client is the connection's peer)")
      ->delimiter(',')
      ->envname("PINTAG_TRUSTED_PROXY");
  AddReplicationOptions(cmd, args->replication);
  // Every option can come from a PINTAG_* variable (shown in --help); a flag given wins.
  cmd->footer(
      "Environment: each option OPTION also reads PINTAG_<OPTION> (upper case, '-' as "
      "'_'), e.g. PINTAG_DB, PINTAG_PORT, PINTAG_LOG_FORMAT; a flag on the command line "
      "wins over the variable.");
  cmd->callback([args] { Run(*args); });
}

const CommandRegistration serve_registration{"serve", &AddServeCommand};

}  // namespace
}  // namespace pintag::cli
