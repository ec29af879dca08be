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
/// symbolic link, the file it names is the one replaced. Anything else (/dev/stdout, a pipe, a
/// device), and a file in a directory this process may not create files in, is written in place.
std::string WriteWholeFile(const std::string& path, std::string_view bytes);

}  // namespace pintag
