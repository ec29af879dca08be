#pragma once
// Writing a whole output file with every error checked, the close included: library writers
// (OpenImageIO's PNG, cv::imwrite, a buffered ofstream) did not check their file's close, so on a
// full disk a small file, its bytes all still buffered, was reported written.

#include <string>
#include <string_view>

namespace pintag {

/// Writes `bytes` to `path`, replacing it: "" when all of it reached the file and the file was
/// closed, else why not (strerror's text). A regular file (or a path not there yet) is written
/// to a new file in its directory, synced to the disk, and renamed over it, the directory synced
/// after: a write that fails, or a crash, leaves what was there before, never a file cut short
/// or empty (a process killed while writing leaves `.pintag-N.tmp` in the directory); through a
/// symbolic link, the file it names is the one replaced (FileReplacedBy; its refusals are the
/// error). Anything else (/dev/stdout, a pipe, a
/// device), and a file in a directory this process may not create files in, is written in place.
std::string WriteWholeFile(const std::string& path, std::string_view bytes);

/// The file a writer that renames a new file into place replaces for `path`, and why it cannot.
struct FileToReplace {
  std::string path;     ///< through a symbolic link, the file it names (the link is kept)
  std::string problem;  ///< empty, or why `path` cannot be replaced by a rename (said whole)
};

/// For writers that must replace a file whole (a snapshot, a token's secret): a regular file or a
/// path not there yet is fine; a device, a pipe or a directory is not (a rename would put a file
/// in its place: `--out /dev/stdout` turned /dev/stdout into a file), nor a loop of links, nor a
/// link another user made in a sticky directory writable by all (the kernel's
/// fs.protected_symlinks rule, which a link read by hand escapes). A link to a file not there
/// yet gives that file's path.
FileToReplace FileReplacedBy(const std::string& path);

}  // namespace pintag
