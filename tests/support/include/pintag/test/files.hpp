#pragma once
// Scratch directories and whole-file reads and writes, for every test suite.

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace pintag::test {

/// A fresh directory under the system temp dir (`<prefix>XXXXXX`), removed with everything in
/// it, even files a test made unreadable. Throws std::runtime_error when it cannot be made.
class TempDir {
 public:
  explicit TempDir(std::string_view prefix = "pintag-test-");
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

/// Writes `content` to `path` (replacing it); returns the path. Throws when it cannot.
std::string WriteFile(const std::filesystem::path& path, std::string_view content);
std::string WriteFile(const std::filesystem::path& path, const std::vector<std::uint8_t>& bytes);
/// The whole file, "" when it cannot be read.
std::string ReadFile(const std::filesystem::path& path);

}  // namespace pintag::test
