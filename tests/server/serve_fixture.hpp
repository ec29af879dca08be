#pragma once
// A real `pintag serve` process for the end-to-end tests: a copy of a seeded database in a
// temporary directory, tokens of every role made in it, the server on a free loopback port
// (--port 0; the port is read from its stdout), and cpp-httplib's client. The process is
// stopped with SIGTERM when the fixture ends (SIGKILL if it does not stop within 5 s), and it
// dies with the test process (PR_SET_PDEATHSIG) if that crashes.

#include <gtest/gtest.h>
#include <httplib.h>

#include <filesystem>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "pintag/test/files.hpp"

namespace pintag::serve_test {

using pintag::test::ReadFile;
using pintag::test::TempDir;
using pintag::test::WriteFile;

/// One `pintag serve` child process.
class ServerProcess {
 public:
  /// Starts `pintag serve --port <port> --bind 127.0.0.1 <args>` (port 0: a free one), stderr to
  /// `stderr_file`, and waits until it printed its URL (at most `timeout_s`). Check ok()
  /// afterwards.
  ServerProcess(const std::vector<std::string>& args, const std::string& stderr_file,
                int timeout_s = 60, int port = 0);
  ~ServerProcess();
  ServerProcess(const ServerProcess&) = delete;
  ServerProcess& operator=(const ServerProcess&) = delete;

  bool ok() const { return port_ > 0; }
  int port() const { return port_; }
  /// Everything the process printed on stdout up to its "Stop with Ctrl-C." line.
  const std::string& out() const { return out_; }
  /// Sends `signal` and waits for the exit; the exit status (or 128 + signal), -1 on timeout.
  int stop(int signal = SIGTERM, int timeout_s = 10);
  /// Waits for the exit (a signal sent before): as stop() without sending one.
  int wait(int timeout_s = 10);
  /// Sends `signal` without waiting.
  void signal(int signal) const;
  /// True while the process has not exited (it is not reaped: stop() still gets its status).
  bool running() const;
  pid_t pid() const { return pid_; }

 private:
  pid_t pid_ = -1;
  int out_fd_ = -1;
  int port_ = 0;
  std::string out_;
};

/// The `pintag` executable under test.
std::string PintagExe();

/// What a finished `pintag` command left.
struct CommandResult {
  int status = -1;  ///< exit status, -1 if it did not exit normally
  std::string out;  ///< stdout and stderr together
};
/// Runs `pintag <arguments>` (a shell command line) and waits for it.
CommandResult RunPintag(const std::string& arguments);
/// Runs `line` with sh -c: its exit status and what it wrote to stdout.
CommandResult RunShell(const std::string& line);
/// As RunPintag, with stdout sent to `stdout_path` instead (stderr alone is in `out`).
CommandResult RunPintagWithStdoutTo(const std::string& arguments, const std::string& stdout_path);
/// Starts `pintag <args>` with descriptor `fd` as its descriptor `as` (a pipe's end as its stdin
/// or stdout) and its stderr written to `stderr_path`, SIGPIPE at its default whatever this
/// process does with it. The child's pid, or -1 when it could not be started; the caller waits.
pid_t SpawnPintagWith(std::vector<std::string> args, int fd, int as,
                      const std::string& stderr_path);
/// The path of a seeded database made once per build (do not modify it).
const std::string& SeededTemplate();

/// `clients` threads, each with its own keep-alive client to 127.0.0.1:`port`, start together and
/// make `calls_each` calls of `call`; returns how many calls `call` judged right.
int CallsRightFromConcurrentClients(int port, int clients, int calls_each,
                                    const std::function<bool(httplib::Client&)>& call);

/// The value of one series (a name, with its labels if any) in a Prometheus text page; 0 when the
/// page has no such line.
double Metric(const std::string& text, const std::string& series);

/// The rows in the scan log at `path` once there are `expected` of them, or what there are after
/// 30 s. An answered scan's row is written by the log's own thread: the answer waits for it up to
/// a second, then no longer (a slow disk, a busy machine), so a test reads the log by waiting.
std::int64_t ScanRowsOnceThereAre(const std::string& path, std::int64_t expected);

/// A fixture with a seeded database copy, one token per role and a running server.
class ServeTest : public ::testing::Test {
 protected:
  void SetUp() override;
  void TearDown() override;

  /// Starts (or restarts) the server with extra serve arguments.
  void startServer(const std::vector<std::string>& extra = {});

  httplib::Client& client() { return *client_; }
  static httplib::Headers Auth(const std::string& token) {
    return {{"Authorization", "Bearer " + token}};
  }
  httplib::Headers admin() const { return Auth(admin_token_); }
  httplib::Headers counter() const { return Auth(counter_token_); }
  httplib::Headers scanner() const { return Auth(scanner_token_); }

  /// The highest key no pincode holds (GET /api/v1/keys/{key} answers 404), found through the
  /// API from 32767 down to 32001; -1 (with a failure) when there is none or a call fails.
  int freeKey();

  /// Asserts a problem+json answer with this status; returns its body.
  static nlohmann::json ExpectProblem(const httplib::Result& r, int status);
  /// Asserts a 200 (or `status`) JSON answer; returns its body.
  static nlohmann::json ExpectJson(const httplib::Result& r, int status = 200);

  TempDir dir_;
  std::string db_path_;
  std::string admin_token_, counter_token_, scanner_token_;
  std::int64_t counter_token_id_ = 0;
  std::unique_ptr<ServerProcess> server_;
  std::unique_ptr<httplib::Client> client_;
};

}  // namespace pintag::serve_test
