#include "commands/unseen_token.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <iostream>
#include <stdexcept>
#include <string>

#include "pintag/codec/file_output.hpp"
#include "pintag/db/tokens.hpp"

namespace pintag::cli {
namespace {

std::string ErrnoText(const std::string& what) {
  return what + ": " + std::strerror(errno);
}

bool WriteAll(int fd, std::string_view bytes) {
  while (!bytes.empty()) {
    const ssize_t n = ::write(fd, bytes.data(), bytes.size());
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    bytes.remove_prefix(static_cast<std::size_t>(n));
  }
  return true;
}

}  // namespace

void RevokeIfUnwritten(db::Connection& connection, std::int64_t id, std::string_view where,
                       std::string_view failure) {
  if (failure.empty()) return;
  const std::string name = std::to_string(id);
  const std::string cannot = "cannot write the secret of token " + name + " to " +
                             std::string(where) + " (" + std::string(failure) + ")";
  auto revoked = db::RevokeToken(connection, id);
  if (!revoked) {
    throw std::runtime_error(cannot + ", and revoking it failed (" + revoked.error().message +
                             "): run `pintag token revoke " + name + "`");
  }
  throw std::runtime_error(cannot + "; the token is revoked");
}

void RevokeIfStdoutFailed(db::Connection& connection, std::int64_t id) {
  if (std::cout) return;
  RevokeIfUnwritten(connection, id, "standard output", "the write failed");
}

std::string WriteSecretFile(const std::filesystem::path& path, std::string_view secret) {
  const FileToReplace target = FileReplacedBy(path.string());
  if (!target.problem.empty()) return target.problem;
  const std::filesystem::path written(target.path);
  const std::filesystem::path directory =
      written.has_parent_path() ? written.parent_path() : std::filesystem::path(".");
  std::string temporary = (directory / ("." + written.filename().string() + ".XXXXXX")).string();
  // mkstemp creates the file 0600 whatever the umask: no moment when others could read it.
  const int fd = ::mkstemp(temporary.data());
  if (fd < 0) return ErrnoText("cannot create a file in " + directory.string());
  std::string failure;
  const std::string line = std::string(secret) + "\n";
  if (!WriteAll(fd, line)) {
    failure = ErrnoText("cannot write " + temporary);
  } else if (::fsync(fd) != 0) {
    failure = ErrnoText("cannot sync " + temporary);
  }
  if (::close(fd) != 0 && failure.empty()) failure = ErrnoText("cannot close " + temporary);
  if (failure.empty() && ::rename(temporary.c_str(), written.c_str()) != 0) {
    failure = ErrnoText("cannot rename " + temporary + " to " + written.string());
  }
  if (!failure.empty()) {
    ::unlink(temporary.c_str());
    return failure;
  }
  // The rename is durable once the directory is synced; a failure here leaves the file in place.
  if (const int dir_fd = ::open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
      dir_fd >= 0) {
    ::fsync(dir_fd);
    ::close(dir_fd);
  }
  return {};
}

}  // namespace pintag::cli
