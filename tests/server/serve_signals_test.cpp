// `pintag serve` beside a thread it did not start and that lets every signal through, as when the
// system BLAS is OpenBLAS (its workers start when the library is loaded, before main()): the
// kernel hands process-directed signals to that thread, and SIGTERM, SIGINT and SIGHUP must still
// do what they do without it. Before the signals had handlers, SIGTERM ended such a server at
// once (exit 143, requests in flight dropped): the README's test command failed on a fresh
// Debian 12 machine, where installing the test packages makes OpenBLAS the BLAS.

#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <thread>

#include "serve_fixture.hpp"

namespace pintag::serve_test {
namespace {

// Sets an environment variable for the processes started while it lives.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv() {
    if (old_) {
      setenv(name_, old_->c_str(), 1);
    } else {
      unsetenv(name_);
    }
  }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  const char* name_;
  std::optional<std::string> old_;
};

// The signal mask of the process's thread named `name`, as /proc shows it; empty when none is.
std::string SignalMaskOfThread(pid_t pid, const std::string& name) {
  for (const auto& task : std::filesystem::directory_iterator(std::filesystem::path("/proc") /
                                                              std::to_string(pid) / "task")) {
    std::string comm;
    std::getline(std::ifstream(task.path() / "comm"), comm);
    if (comm != name) continue;
    std::ifstream status(task.path() / "status");
    for (std::string line; std::getline(status, line);) {
      if (line.rfind("SigBlk:", 0) == 0) return line.substr(line.find_first_not_of(" \t", 7));
    }
  }
  return {};
}

class ServeBesideAnUnblockedThread : public ServeTest {
 protected:
  void SetUp() override {
    ServeTest::SetUp();  // a plain server first: the fixture's tokens and database
    if (HasFatalFailure()) return;
    // An ASan runtime wants to be first in the library list; the preloaded library comes first.
    const char* asan = std::getenv("ASAN_OPTIONS");
    ScopedEnv asan_order("ASAN_OPTIONS",
                         std::string(asan ? asan : "") + ":verify_asan_link_order=0");
    ScopedEnv preload("LD_PRELOAD", PINTAG_UNBLOCKED_THREAD_PRELOAD);
    startServer();
    if (HasFatalFailure()) return;
    ASSERT_EQ(SignalMaskOfThread(server_->pid(), "unblocked"), "0000000000000000")
        << "the preloaded thread is missing or blocks signals: the test would prove nothing";
  }

  bool answers() {
    const auto r = client().Get("/livez");
    return r && r->status == 200;
  }
};

TEST_F(ServeBesideAnUnblockedThread, SigtermStopsItGracefully) {
  ASSERT_TRUE(answers());
  EXPECT_EQ(server_->stop(SIGTERM, 20), 0);
  EXPECT_NE(ReadFile(dir_.file("stderr.log")).find("SIGTERM, finishing requests in flight"),
            std::string::npos);
}

TEST_F(ServeBesideAnUnblockedThread, SigintStopsItGracefully) {
  ASSERT_TRUE(answers());
  EXPECT_EQ(server_->stop(SIGINT, 20), 0);
  EXPECT_NE(ReadFile(dir_.file("stderr.log")).find("SIGINT, finishing requests in flight"),
            std::string::npos);
}

TEST_F(ServeBesideAnUnblockedThread, SighupDoesNotEndIt) {
  server_->signal(SIGHUP);
  server_->signal(SIGHUP);
  // The reloads (nothing to reload on a primary) go through the waiter while it keeps serving.
  for (int i = 0; i < 20; ++i) {
    ASSERT_TRUE(server_->running()) << "SIGHUP ended the server";
    ASSERT_TRUE(answers());
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  EXPECT_EQ(server_->stop(SIGTERM, 20), 0);
}

}  // namespace
}  // namespace pintag::serve_test
