#include "serve_fixture.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <regex>
#include <sstream>
#include <thread>
#include <vector>

#include "pintag/db/database.hpp"
#include "pintag/db/sqlite.hpp"
#include "pintag/db/tokens.hpp"
#include "pintag/test/seeded_db.hpp"

namespace pintag::serve_test {

std::string PintagExe() {
  return PINTAG_EXE;
}

int CallsRightFromConcurrentClients(int port, int clients, int calls_each,
                                    const std::function<bool(httplib::Client&)>& call) {
  std::atomic<int> ready{0}, right{0};
  std::vector<std::thread> threads;
  threads.reserve(static_cast<std::size_t>(clients));
  for (int c = 0; c < clients; ++c) {
    threads.emplace_back([&] {
      httplib::Client client("127.0.0.1", port);
      client.set_read_timeout(60, 0);
      ++ready;
      while (ready < clients) std::this_thread::yield();  // all start together
      for (int i = 0; i < calls_each; ++i) right += call(client) ? 1 : 0;
    });
  }
  for (std::thread& t : threads) t.join();
  return right;
}

double Metric(const std::string& text, const std::string& series) {
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    if (line.rfind(series + " ", 0) == 0) return std::stod(line.substr(series.size() + 1));
  }
  return 0;
}

std::int64_t ScanRowsOnceThereAre(const std::string& path, std::int64_t expected) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (true) {
    std::int64_t rows = -1;
    try {
      db::Connection connection(path, {.create = false, .read_only = true});
      rows = connection.queryInt64("SELECT count(*) FROM scan_log");
    } catch (const std::exception&) {
      // Not there yet, or locked for a moment: asked again.
    }
    if (rows >= expected || std::chrono::steady_clock::now() > deadline) return rows;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
}

CommandResult RunShell(const std::string& line) {
  CommandResult result;
  FILE* pipe = ::popen(line.c_str(), "r");
  if (pipe == nullptr) return result;
  std::array<char, 4096> buffer{};
  std::size_t n = 0;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0)
    result.out.append(buffer.data(), n);
  const int raw = ::pclose(pipe);
  if (WIFEXITED(raw)) result.status = WEXITSTATUS(raw);
  return result;
}

CommandResult RunPintag(const std::string& arguments) {
  return RunShell(PintagExe() + " " + arguments + " 2>&1");
}

CommandResult RunPintagWithStdoutTo(const std::string& arguments, const std::string& stdout_path) {
  // 2>&1 first: stderr to the pipe, then stdout alone to the file.
  return RunShell(PintagExe() + " " + arguments + " 2>&1 >" + stdout_path);
}

pid_t SpawnPintagWith(std::vector<std::string> args, int fd, int as,
                      const std::string& stderr_path) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fd, as);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, stderr_path.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  sigset_t pipe_signal;
  sigemptyset(&pipe_signal);
  sigaddset(&pipe_signal, SIGPIPE);
  posix_spawnattr_setsigdefault(&attributes, &pipe_signal);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGDEF);
  args.insert(args.begin(), PintagExe());
  std::vector<char*> argv;
  argv.reserve(args.size() + 1);
  for (std::string& word : args) argv.push_back(word.data());
  argv.push_back(nullptr);
  pid_t pid = -1;
  const int spawned = ::posix_spawn(&pid, argv[0], &actions, &attributes, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  return spawned == 0 ? pid : -1;
}

ServerProcess::ServerProcess(const std::vector<std::string>& args, const std::string& stderr_file,
                             int timeout_s, int port) {
  int pipe_fds[2];
  if (::pipe2(pipe_fds, O_CLOEXEC) != 0) return;
  std::vector<std::string> argv_text = {PintagExe(),          "serve",  "--port",
                                        std::to_string(port), "--bind", "127.0.0.1"};
  argv_text.insert(argv_text.end(), args.begin(), args.end());
  std::vector<char*> argv;
  argv.reserve(argv_text.size() + 1);
  for (std::string& a : argv_text) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t parent = ::getpid();
  pid_ = ::fork();
  if (pid_ == 0) {
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(127);
    ::dup2(pipe_fds[1], 1);
    const int err = ::open(stderr_file.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0600);
    if (err >= 0) ::dup2(err, 2);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  ::close(pipe_fds[1]);
  out_fd_ = pipe_fds[0];
  if (pid_ < 0) return;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(timeout_s);
  while (out_.find("Stop with Ctrl-C.") == std::string::npos) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return;
    pollfd p{out_fd_, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(left.count())) <= 0) return;
    char buffer[4096];
    const ssize_t n = ::read(out_fd_, buffer, sizeof buffer);
    if (n <= 0) return;  // exited
    out_.append(buffer, static_cast<std::size_t>(n));
  }
  std::smatch match;
  if (std::regex_search(out_, match, std::regex(R"(serving http://127\.0\.0\.1:(\d+)/)"))) {
    port_ = std::stoi(match[1].str());
  }
}

void ServerProcess::signal(int signal) const {
  if (pid_ > 0) ::kill(pid_, signal);
}

bool ServerProcess::running() const {
  if (pid_ <= 0) return false;
  siginfo_t info{};
  if (::waitid(P_PID, static_cast<id_t>(pid_), &info, WEXITED | WNOHANG | WNOWAIT) != 0) {
    return false;
  }
  return info.si_pid == 0;  // nothing to report yet
}

int ServerProcess::stop(int signal, int timeout_s) {
  if (pid_ <= 0) return -1;
  ::kill(pid_, signal);
  return wait(timeout_s);
}

int ServerProcess::wait(int timeout_s) {
  if (pid_ <= 0) return -1;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(timeout_s);
  int status = 0;
  while (std::chrono::steady_clock::now() < deadline) {
    const pid_t done = ::waitpid(pid_, &status, WNOHANG);
    if (done == pid_) {
      pid_ = -1;
      return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return -1;
}

ServerProcess::~ServerProcess() {
  if (pid_ > 0 && stop(SIGTERM, 5) == -1 && pid_ > 0) {
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, nullptr, 0);
  }
  if (out_fd_ >= 0) ::close(out_fd_);
}

// ctest runs each test in its own process: seed once per build of this executable, not per test.
const std::string& SeededTemplate() {
  static const std::string path = pintag::test::SeededTemplate(PINTAG_TEST_TEMPLATE_DIR);
  return path;
}

void ServeTest::SetUp() {
  db_path_ = dir_.file("registry.db");
  std::filesystem::copy_file(SeededTemplate(), db_path_);
  {
    auto opened = db::OpenDatabase(db_path_, {.create = false});
    ASSERT_TRUE(opened) << opened.error().message;
    auto admin = db::CreateToken(opened.value().connection, db::Role::kAdmin, "test admin");
    auto counter = db::CreateToken(opened.value().connection, db::Role::kCounter, "test counter");
    auto scanner = db::CreateToken(opened.value().connection, db::Role::kScanner, "test scanner");
    ASSERT_TRUE(admin && counter && scanner);
    admin_token_ = admin->secret;
    counter_token_ = counter->secret;
    counter_token_id_ = counter->info.id;
    scanner_token_ = scanner->secret;
  }
  startServer();
}

void ServeTest::startServer(const std::vector<std::string>& extra) {
  client_.reset();
  server_.reset();
  std::vector<std::string> args = {"--db", db_path_, "--threads", "4"};
  args.insert(args.end(), extra.begin(), extra.end());
  server_ = std::make_unique<ServerProcess>(args, dir_.file("stderr.log"));
  ASSERT_TRUE(server_->ok()) << "pintag serve did not start; stdout:\n"
                             << server_->out() << "\nstderr:\n"
                             << ReadFile(dir_.file("stderr.log"));
  client_ = std::make_unique<httplib::Client>("127.0.0.1", server_->port());
  client_->set_read_timeout(30, 0);
  client_->set_write_timeout(30, 0);
}

void ServeTest::TearDown() {
  client_.reset();
  server_.reset();  // SIGTERM, SIGKILL after 5 s
  if (HasFailure()) std::cerr << "server stderr:\n" << ReadFile(dir_.file("stderr.log"));
}

nlohmann::json ServeTest::ExpectProblem(const httplib::Result& r, int status) {
  EXPECT_TRUE(r) << "no response: " << httplib::to_string(r.error());
  if (!r) return {};
  EXPECT_EQ(r->status, status) << r->body.substr(0, 500);
  EXPECT_EQ(r->get_header_value("Content-Type"), "application/problem+json")
      << r->body.substr(0, 300);
  nlohmann::json body = nlohmann::json::parse(r->body, nullptr, false);
  EXPECT_FALSE(body.is_discarded()) << r->body.substr(0, 300);
  if (body.is_discarded()) return {};
  EXPECT_EQ(body.value("status", 0), status);
  EXPECT_TRUE(body.contains("type") && body.contains("title") && body.contains("detail"))
      << r->body;
  return body;
}

nlohmann::json ServeTest::ExpectJson(const httplib::Result& r, int status) {
  EXPECT_TRUE(r) << "no response: " << httplib::to_string(r.error());
  if (!r) return {};
  EXPECT_EQ(r->status, status) << r->body.substr(0, 500);
  EXPECT_EQ(r->get_header_value("Content-Type").rfind("application/json", 0), 0U);
  nlohmann::json body = nlohmann::json::parse(r->body, nullptr, false);
  EXPECT_FALSE(body.is_discarded()) << r->body.substr(0, 300);
  return body.is_discarded() ? nlohmann::json() : body;
}

int ServeTest::freeKey() {
  for (int key = 32767; key > 32000; --key) {
    const auto r = client().Get("/api/v1/keys/" + std::to_string(key));
    EXPECT_TRUE(r);
    if (!r) return -1;
    if (r->status == 404) return key;
  }
  return -1;
}

}  // namespace pintag::serve_test
