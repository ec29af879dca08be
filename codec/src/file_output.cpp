#include "pintag/codec/file_output.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace pintag {

std::string WriteWholeFile(const std::string& path, std::string_view bytes) {
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) return std::strerror(errno);
  errno = 0;
  int failure = 0;
  if (std::fwrite(bytes.data(), 1, bytes.size(), file) != bytes.size()) {
    failure = errno != 0 ? errno : EIO;  // a short write that set no errno is still a failure
  }
  if (std::fclose(file) != 0 && failure == 0) failure = errno != 0 ? errno : EIO;
  return failure == 0 ? std::string() : std::strerror(failure);
}

}  // namespace pintag
