#include "nginx_process.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <thread>

#include "pintag/test/files.hpp"
#include "pintag/test/loopback_socket.hpp"

namespace pintag::serve_test {
namespace {

std::string NginxExe() {
  for (const char* path : {"/usr/sbin/nginx", "/usr/bin/nginx"}) {
    if (::access(path, X_OK) == 0) return path;
  }
  return "";
}

/// Runs argv to completion; its exit status, -1 when it could not run.
int Run(std::vector<std::string> args) {
  std::vector<char*> argv;
  argv.reserve(args.size() + 1);
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  int status = 0;
  if (pid < 0 || ::waitpid(pid, &status, 0) != pid) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string Address(int port) {
  return "127.0.0.1:" + std::to_string(port);
}

}  // namespace

int FreeLoopbackPort() {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t size = sizeof address;
  int port = 0;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0 &&
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &size) == 0) {
    port = ntohs(address.sin_port);
  }
  ::close(fd);
  return port;
}

NginxProcess::NginxProcess(const std::filesystem::path& prefix, int primary_port,
                           const std::vector<int>& replica_ports)
    : prefix_(prefix) {
  // The port is free when picked and taken by nginx a moment later; another test's server may
  // bind it in between. nginx then cannot listen, and a connection to the port reaches that other
  // server: such an attempt is made again on another port.
  for (int attempt = 0; attempt < 3; ++attempt) {
    if (start(primary_port, replica_ports) != Start::kPortTaken) return;
  }
}

NginxProcess::Start NginxProcess::start(int primary_port, const std::vector<int>& replica_ports) {
  const std::string nginx = NginxExe();
  if (nginx.empty()) {
    error_ = "nginx is not installed (Debian's nginx-light, in scripts/debian-packages-test.txt)";
    return Start::kFailed;
  }
  port_ = FreeLoopbackPort();
  const std::string source = PINTAG_SOURCE_DIR;
  std::vector<std::string> render = {"/bin/sh",
                                     source + "/docker/nginx/render-conf.sh",
                                     source + "/docker/nginx/pintag.conf.template",
                                     prefix_.string(),
                                     Address(port_),
                                     Address(primary_port)};
  for (const int port : replica_ports) render.push_back(Address(port));
  if (Run(render) != 0) {
    error_ = "render-conf.sh failed";
    return Start::kFailed;
  }
  // As root, nginx's workers run as nobody: they must reach the prefix (in the test's own
  // directory) to write temporary files.
  ::chmod(prefix_.parent_path().c_str(), 0755);
  ::chmod(prefix_.c_str(), 0755);
  const std::string error_log = (prefix_ / "stderr.log").string();
  // The log is appended to by every attempt: this one's part starts here.
  const std::size_t log_start = test::ReadFile(error_log).size();
  const auto this_log = [&] {
    const std::string log = test::ReadFile(error_log);
    return log.size() > log_start ? log.substr(log_start) : std::string();
  };
  const pid_t parent = ::getpid();
  pid_ = ::fork();
  if (pid_ == 0) {
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(127);
    const int err = ::open(error_log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    if (err >= 0) {
      ::dup2(err, 1);
      ::dup2(err, 2);
    }
    const std::string conf = (prefix_ / "nginx.conf").string();
    ::execl(nginx.c_str(), nginx.c_str(), "-p", prefix_.c_str(), "-e", "stderr", "-c", conf.c_str(),
            "-g", "daemon off;", static_cast<char*>(nullptr));
    ::_exit(127);
  }
  if (pid_ < 0) {
    error_ = std::string("cannot fork nginx: ") + std::strerror(errno);
    return Start::kFailed;
  }
  const auto port_taken = [&] {
    if (pid_ > 0) {  // never kill(-1, …): that signals every process we may signal
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
      pid_ = -1;
    }
    error_ = "another server took " + Address(port_) + " before nginx: " + this_log();
    return Start::kPortTaken;
  };
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (std::chrono::steady_clock::now() < deadline) {
    if (::waitpid(pid_, nullptr, WNOHANG) == pid_) {
      pid_ = -1;  // reaped
      const std::string log = this_log();
      if (log.find("Address already in use") != std::string::npos) return port_taken();
      error_ = "nginx exited: " + log;
      return Start::kFailed;
    }
    // Whoever answers must be nginx (it names itself in every answer, proxied or its own).
    const std::string answer = test::SendRaw(port_, "GET /livez HTTP/1.0\r\n\r\n", 10);
    if (!answer.empty()) {
      if (answer.find("\r\nServer: nginx") == std::string::npos) return port_taken();
      error_.clear();
      return Start::kStarted;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  error_ = "nginx did not listen on " + Address(port_) + ": " + this_log();
  return Start::kFailed;
}

NginxProcess::~NginxProcess() {
  if (pid_ <= 0) return;
  ::kill(pid_, SIGQUIT);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (std::chrono::steady_clock::now() < deadline) {
    if (::waitpid(pid_, nullptr, WNOHANG) == pid_) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ::kill(pid_, SIGKILL);
  ::waitpid(pid_, nullptr, 0);
}

std::string NginxProcess::logs() const {
  return test::ReadFile(prefix_ / "stderr.log") + test::ReadFile(prefix_ / "logs/access.log");
}

}  // namespace pintag::serve_test
