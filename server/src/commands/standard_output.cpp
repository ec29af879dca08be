#include "commands/standard_output.hpp"

#include <poll.h>
#include <sys/stat.h>
#include <unistd.h>

namespace pintag::cli {

bool StandardOutputReaderHasGone() {
  struct stat about {};
  if (::fstat(STDOUT_FILENO, &about) != 0) return false;
  if (!S_ISFIFO(about.st_mode) && !S_ISSOCK(about.st_mode)) return false;
  // Linux reports POLLERR on a pipe's write end once every reader has closed it, and POLLHUP or
  // POLLERR on a socket whose peer has gone; neither waits.
  pollfd out{STDOUT_FILENO, POLLOUT, 0};
  if (::poll(&out, 1, 0) != 1) return false;
  return (out.revents & (POLLERR | POLLHUP)) != 0;
}

}  // namespace pintag::cli
