#include "pintag/codec/file_output.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

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

// A rename replaces a link itself, so FileReplacedBy follows links by hand; the kernel's rule
// for links in shared directories (fs.protected_symlinks) then has to be applied by hand too.
TEST(FileReplacedBy, FollowsLinksButNotAnotherUsersLinkInASharedDirectory) {
  test::TempDir dir;
  const std::filesystem::path shared = dir.path() / "shared";
  std::filesystem::create_directory(shared);
  ASSERT_EQ(::chmod(shared.c_str(), 01777), 0);  // as /tmp: sticky, writable by all
  const std::filesystem::path target = dir.path() / "victim";
  test::WriteFile(target, "kept\n");
  const std::filesystem::path link = shared / "out";
  std::filesystem::create_symlink(target, link);

  // This user's own link, in a shared directory or not, names the file written.
  FileToReplace followed = FileReplacedBy(link.string());
  EXPECT_EQ(followed.problem, "");
  EXPECT_TRUE(std::filesystem::equivalent(followed.path, target)) << followed.path;
  std::filesystem::create_symlink("../victim", dir.path() / "shared" / "relative");
  followed = FileReplacedBy((shared / "relative").string());
  EXPECT_EQ(followed.problem, "");
  EXPECT_TRUE(std::filesystem::equivalent(followed.path, target)) << followed.path;

  // Another user's link there (only root can make one here, and only where uid 65534 exists: as
  // another user the case cannot be set up): refused, and never written through, whether the
  // file it names is there or not.
  const std::filesystem::path dangling = shared / "to-new";
  std::filesystem::create_symlink(dir.path() / "made-through-the-link", dangling);
  if (::geteuid() == 0 && ::lchown(link.c_str(), 65534, 65534) == 0 &&
      ::lchown(dangling.c_str(), 65534, 65534) == 0) {
    EXPECT_NE(WriteWholeFile(dangling.string(), "x\n"), "");
    EXPECT_FALSE(std::filesystem::exists(dir.path() / "made-through-the-link"));
    const FileToReplace refused = FileReplacedBy(link.string());
    EXPECT_NE(refused.problem.find("a symbolic link another user made in a shared directory"),
              std::string::npos)
        << refused.problem;
    // Reached through a link of this user's own: the message names the link refused.
    std::filesystem::create_symlink(link, dir.path() / "mine");
    const FileToReplace through = FileReplacedBy((dir.path() / "mine").string());
    EXPECT_NE(through.problem.find("leads to " + link.string() + ", which is a symbolic link"),
              std::string::npos)
        << through.problem;
    EXPECT_NE(WriteWholeFile(link.string(), "secret\n"), "");
    EXPECT_EQ(test::ReadFile(target), "kept\n");
    // The same link in a directory that is not shared is followed.
    ASSERT_EQ(::chmod(shared.c_str(), 0755), 0);
    EXPECT_EQ(FileReplacedBy(link.string()).problem, "");
  }

  // Devices, pipes and directories are refused; a loop of links too.
  EXPECT_NE(FileReplacedBy("/dev/null").problem.find("is a device, not a file"), std::string::npos);
  EXPECT_NE(FileReplacedBy(dir.path().string()).problem.find("is a directory"), std::string::npos);
  std::filesystem::create_symlink("loop-b", dir.path() / "loop-a");
  std::filesystem::create_symlink("loop-a", dir.path() / "loop-b");
  EXPECT_NE(FileReplacedBy((dir.path() / "loop-a").string()).problem.find("a loop?"),
            std::string::npos);
}

}  // namespace
}  // namespace pintag
