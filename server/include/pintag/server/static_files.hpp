#pragma once
// Static files from the web directory, with no way out of it: only plain path characters, no
// ".." or hidden segments, and the resolved real path (symlinks followed) must stay inside the
// directory's real path.

#include <filesystem>
#include <string_view>

#include "pintag/server/http_types.hpp"

namespace pintag::server {

class StaticFiles {
 public:
  /// `root` must exist; it is resolved once (realpath) here. Throws std::invalid_argument if not.
  explicit StaticFiles(const std::filesystem::path& root);

  /// The file for a decoded URL path ("/" and directories serve index.html). A problem+json 404
  /// for anything missing or refused (refusals do not say why, to leak nothing about the disk).
  HttpResponse serve(std::string_view url_path) const;

  /// Whether the path is even a candidate (characters and segments); exposed for tests.
  static bool IsSafeUrlPath(std::string_view url_path);

  const std::filesystem::path& root() const { return root_; }

 private:
  std::filesystem::path root_;
};

/// Media type by file extension (html, js, css, svg, png, json, …); application/octet-stream else.
std::string_view MediaTypeFor(const std::filesystem::path& path);

}  // namespace pintag::server
