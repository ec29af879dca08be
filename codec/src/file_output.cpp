#include "pintag/codec/file_output.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <random>

namespace pintag {
namespace {

/// Writes all of `bytes` to `fd`, with `sync` flushes them to the disk, and closes it: 0, or the
/// errno of the first failure.
int WriteAndClose(int fd, std::string_view bytes, bool sync) {
  int failure = 0;
  for (std::size_t written = 0; written < bytes.size() && failure == 0;) {
    const ssize_t n = ::write(fd, bytes.data() + written, bytes.size() - written);
    if (n > 0) {
      written += static_cast<std::size_t>(n);
    } else if (n < 0 && errno != EINTR) {
      failure = errno;
    } else if (n == 0) {
      failure = EIO;  // a write that took nothing and said nothing is still a failure
    }
  }
  // Before the rename: else a crash can leave the new name on a file whose bytes never landed.
  if (sync && failure == 0 && ::fsync(fd) != 0) failure = errno;
  if (::close(fd) != 0 && failure == 0) failure = errno;
  return failure;
}

/// The directory `path` is in ("." for a bare name).
std::string DirectoryOf(const std::string& path) {
  const std::size_t slash = path.rfind('/');
  if (slash == std::string::npos) return ".";
  return slash == 0 ? "/" : path.substr(0, slash);
}

/// Makes a rename in `directory` durable: 0, or the errno of the failure. A file system that
/// cannot sync a directory (EINVAL) is taken at its word.
int SyncDirectory(const std::string& directory) {
  const int fd = ::open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return errno == EACCES ? 0 : errno;  // a directory we may write but not read
  int failure = ::fsync(fd) != 0 && errno != EINVAL ? errno : 0;
  if (::close(fd) != 0 && failure == 0) failure = errno;
  return failure;
}

/// Whether this process may follow the link at `link` (`st` its lstat): the kernel's
/// fs.protected_symlinks rule, applied here because a link read with readlink() is not checked
/// by the kernel. In a sticky directory writable by all (/tmp), a link is followed only when this
/// user or the directory's owner owns it: another user's link there could aim a secret or a
/// snapshot at any file this process may write.
bool MayFollow(const std::string& link, const struct stat& st) {
  struct stat directory {};
  if (::stat(DirectoryOf(link).c_str(), &directory) != 0) return false;
  const bool shared = (directory.st_mode & S_ISVTX) != 0 && (directory.st_mode & S_IWOTH) != 0;
  return !shared || st.st_uid == ::geteuid() || st.st_uid == directory.st_uid;
}

/// Where a path leads once its links are followed, or why they may not be.
struct FollowedLinks {
  std::string path;     ///< the first path on the way that is not a link (there or not)
  std::string problem;  ///< a loop, another user's link in a shared directory, an unreadable one
};

/// Follows the links at `path` hop by hop, as open() would, with the kernel's rule for links in
/// shared directories (MayFollow) applied to each: a rename replaces a link itself, so writers
/// that rename resolve the link first, and that escapes the kernel's own check.
FollowedLinks FollowLinks(const std::string& path) {
  FollowedLinks out{path, {}};
  for (int hop = 0;; ++hop) {
    struct stat st {};
    if (::lstat(out.path.c_str(), &st) != 0) {
      if (errno != ENOENT) out.problem = path + ": " + std::strerror(errno);
      return out;  // not there: made at this path
    }
    if (!S_ISLNK(st.st_mode)) return out;
    const std::string named = out.path == path ? path : path + " leads to " + out.path + ", which";
    if (hop == 40) {
      out.problem = named + " is a symbolic link that cannot be followed (a loop?)";
      return out;
    }
    if (!MayFollow(out.path, st)) {
      out.problem = named +
                    " is a symbolic link another user made in a shared directory (sticky and "
                    "writable by all, as /tmp); name the file itself";
      return out;
    }
    std::string to(PATH_MAX, '\0');
    const ssize_t n = ::readlink(out.path.c_str(), to.data(), to.size());
    if (n < 0) {
      out.problem = named + " cannot be read as a symbolic link (" + std::strerror(errno) + ")";
      return out;
    }
    to.resize(static_cast<std::size_t>(n));
    out.path = to.starts_with('/') ? to : DirectoryOf(out.path) + "/" + to;
  }
}

/// Creates a new file in `directory` as open() creates one (0666 less the umask), and names it in
/// `name`: its descriptor, or -1 with errno set. The name is short whatever the destination's:
/// the destination's own name with a suffix overran NAME_MAX for a legal name of 246 bytes.
int CreateIn(const std::string& directory, std::string& name) {
  std::random_device random;
  for (int attempt = 0; attempt < 100; ++attempt) {
    name = directory + "/.pintag-" + std::to_string(random()) + ".tmp";
    const int fd = ::open(name.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd >= 0 || errno != EEXIST) return fd;
  }
  errno = EEXIST;
  return -1;
}

}  // namespace

std::string WriteWholeFile(const std::string& path, std::string_view bytes) {
  // Links are followed by hand, the kernel's rule for shared directories with them, before a
  // file is opened in place or renamed over: a link another user left in /tmp could otherwise
  // aim a write at a file, or a device, this process may write.
  const FollowedLinks followed = FollowLinks(path);
  if (!followed.problem.empty()) return followed.problem;
  const std::string& destination = followed.path;
  struct stat target {};
  const bool exists = ::stat(destination.c_str(), &target) == 0;
  const auto in_place = [&]() -> std::string {
    const int fd = ::open(destination.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (fd < 0) return std::strerror(errno);
    const int failure = WriteAndClose(fd, bytes, false);  // fsync fails on a pipe or a tty
    return failure == 0 ? std::string() : std::strerror(failure);
  };
  if (exists && !S_ISREG(target.st_mode)) return in_place();  // /dev/stdout, a pipe, a device
  const std::string directory = DirectoryOf(destination);
  std::string temporary;
  const int fd = CreateIn(directory, temporary);
  if (fd < 0) {
    // A file that may be written in a directory that may not: written in place, as before.
    if (exists && (errno == EACCES || errno == EPERM || errno == EROFS)) return in_place();
    return std::strerror(errno);
  }
  // A file replaced keeps its mode; a new one has the umask's, as open() gave it.
  int failure = exists && ::fchmod(fd, target.st_mode & 07777) != 0 ? errno : 0;
  if (failure != 0) {
    ::close(fd);
  } else {
    failure = WriteAndClose(fd, bytes, true);
  }
  if (failure == 0 && ::rename(temporary.c_str(), destination.c_str()) != 0) failure = errno;
  if (failure != 0) {
    ::unlink(temporary.c_str());
    return std::strerror(failure);
  }
  // The rename itself is durable only once the directory is synced.
  if (const int synced = SyncDirectory(directory); synced != 0) return std::strerror(synced);
  return {};
}

FileToReplace FileReplacedBy(const std::string& path) {
  const FollowedLinks followed = FollowLinks(path);
  FileToReplace out{followed.path, followed.problem};
  struct stat st {};
  if (!out.problem.empty() || ::stat(out.path.c_str(), &st) != 0 || S_ISREG(st.st_mode)) {
    return out;
  }
  out.problem = path + " is " +
                (S_ISDIR(st.st_mode)    ? "a directory"
                 : S_ISFIFO(st.st_mode) ? "a pipe"
                 : S_ISSOCK(st.st_mode) ? "a socket"
                                        : "a device") +
                ", not a file: the output is written beside it and renamed into place";
  return out;
}

}  // namespace pintag
