#include "pintag/test/loopback_socket.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <cstdint>

namespace pintag::test {

int ConnectLoopback(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return -1;
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

bool SendAll(int fd, const std::string& bytes) {
  std::size_t sent = 0;
  while (sent < bytes.size()) {
    const ssize_t n = ::send(fd, bytes.data() + sent, bytes.size() - sent, MSG_NOSIGNAL);
    if (n <= 0) return false;
    sent += static_cast<std::size_t>(n);
  }
  return true;
}

std::string ReceiveUntil(int fd, int quiet_s, const std::function<bool(const std::string&)>& done) {
  timeval timeout{quiet_s, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  std::string out;
  char buffer[65536];
  ssize_t n = 0;
  while ((n = ::recv(fd, buffer, sizeof buffer, 0)) > 0) {
    out.append(buffer, static_cast<std::size_t>(n));
    if (done && done(out)) break;
  }
  return out;
}

bool HasWholeResponse(const std::string& received) {
  const std::size_t end = received.find("\r\n\r\n");
  if (end == std::string::npos) return false;
  const std::size_t length = received.find("Content-Length: ");
  if (length == std::string::npos || length > end) return true;
  return received.size() >= end + 4 + std::stoul(received.substr(length + 16));
}

std::string SendRaw(int port, const std::string& request, int quiet_s,
                    const std::function<bool(const std::string&)>& done) {
  const int fd = ConnectLoopback(port);
  if (fd < 0) return {};
  SendAll(fd, request);
  std::string out = ReceiveUntil(fd, quiet_s, done);
  ::close(fd);
  return out;
}

}  // namespace pintag::test
