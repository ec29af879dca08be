#include "pintag/codec/file_output.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "pintag/test/files.hpp"

namespace pintag {
namespace {

std::vector<std::string> Entries(const std::filesystem::path& directory) {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(directory)) {
    names.push_back(entry.path().filename().string());
  }
  return names;
}

TEST(WriteWholeFile, WritesAndReplacesAFileWithTheLongestLegalName) {
  // The temporary file was named after the destination plus ".tmp-" and ten digits: a legal
  // 250-byte name (NAME_MAX is 255) failed with "File name too long".
  test::TempDir dir;
  const std::string name = std::string(246, 'n') + ".png";
  ASSERT_EQ(name.size(), 250U);
  const std::filesystem::path path = dir.path() / name;
  EXPECT_EQ(WriteWholeFile(path.string(), "first\n"), "");
  EXPECT_EQ(test::ReadFile(path), "first\n");
  EXPECT_EQ(WriteWholeFile(path.string(), "second\n"), "");  // replaced through a rename
  EXPECT_EQ(test::ReadFile(path), "second\n");
  EXPECT_EQ(Entries(dir.path()), std::vector<std::string>{name}) << "a temporary file was left";
}

TEST(WriteWholeFile, ReportsAMissingDirectoryAndLeavesNothing) {
  test::TempDir dir;
  EXPECT_NE(WriteWholeFile((dir.path() / "absent" / "label.png").string(), "x"), "");
  EXPECT_TRUE(Entries(dir.path()).empty());
}

}  // namespace
}  // namespace pintag
