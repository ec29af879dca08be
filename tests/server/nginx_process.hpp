#pragma once
// Debian's nginx in front of a primary and its replicas, configured from the same template the
// Docker image uses (docker/nginx/pintag.conf.template, rendered by render-conf.sh), listening on
// a free loopback port. Runs in the foreground as a child that dies with the test process.

#include <sys/types.h>

#include <filesystem>
#include <string>
#include <vector>

namespace pintag::serve_test {

class NginxProcess {
 public:
  /// Renders the configuration into `prefix` (a new directory inside a test's scratch directory,
  /// both made readable to nginx's workers) and starts nginx; waits (at most 30 s) until nginx
  /// answers on its port (on another port when a server took that one first). Check ok()
  /// afterwards; error() says why not.
  NginxProcess(const std::filesystem::path& prefix, int primary_port,
               const std::vector<int>& replica_ports);
  ~NginxProcess();  ///< graceful stop (SIGQUIT), SIGKILL after 10 s
  NginxProcess(const NginxProcess&) = delete;
  NginxProcess& operator=(const NginxProcess&) = delete;

  bool ok() const { return error_.empty(); }
  const std::string& error() const { return error_; }
  int port() const { return port_; }
  /// nginx's error log (its stderr) and access log so far.
  std::string logs() const;

 private:
  enum class Start { kStarted, kPortTaken, kFailed };
  /// One attempt on a freshly picked port.
  Start start(int primary_port, const std::vector<int>& replica_ports);

  std::filesystem::path prefix_;
  pid_t pid_ = -1;
  int port_ = 0;
  std::string error_;
};

/// A loopback port that was free a moment ago (bound to port 0, then released).
int FreeLoopbackPort();

}  // namespace pintag::serve_test
