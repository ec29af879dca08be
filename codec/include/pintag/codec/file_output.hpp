#pragma once
// Writing a whole output file with every error checked, the close included: library writers
// (OpenImageIO's PNG, cv::imwrite, a buffered ofstream) did not check their file's close, so on a
// full disk a small file, its bytes all still buffered, was reported written.

#include <string>
#include <string_view>

namespace pintag {

/// Writes `bytes` to `path`, replacing it: "" when all of it reached the file and the file was
/// closed, else why not (strerror's text).
std::string WriteWholeFile(const std::string& path, std::string_view bytes);

}  // namespace pintag
