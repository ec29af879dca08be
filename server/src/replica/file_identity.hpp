#pragma once
// Which file is at a path, and whether it changed: device, inode, size and modification time.
// A snapshot renamed into place is another inode; one overwritten in place changes size or time.

#include <sys/stat.h>

#include <cstdint>
#include <optional>
#include <string>

namespace pintag::replica {

struct FileIdentity {
  std::uint64_t device = 0;
  std::uint64_t inode = 0;
  std::int64_t size = 0;
  std::int64_t modified_ns = 0;
  bool operator==(const FileIdentity&) const = default;
};

/// The identity of the file at `path`; nothing when there is none (or it cannot be looked at).
inline std::optional<FileIdentity> IdentifyFile(const std::string& path) {
  struct stat status {};
  if (::stat(path.c_str(), &status) != 0) return std::nullopt;
  return FileIdentity{status.st_dev, status.st_ino, status.st_size,
                      std::int64_t{status.st_mtim.tv_sec} * 1'000'000'000 + status.st_mtim.tv_nsec};
}

}  // namespace pintag::replica
