#include "pintag/server/static_files.hpp"

#include <array>
#include <climits>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <utility>

#include "pintag/server/problem.hpp"

namespace pintag::server {
namespace {

constexpr std::size_t kMaxUrlPath = 1024;
constexpr std::uintmax_t kMaxFileBytes = std::uintmax_t{64} * 1024 * 1024;
constexpr std::string_view kPagePolicy =
    "default-src 'self'; img-src 'self' blob:; object-src 'none'; base-uri 'none'; "
    "form-action 'self'; frame-ancestors 'self'";

// realpath(3): the canonical absolute path with every symlink resolved; nothing if missing.
std::optional<std::filesystem::path> RealPath(const std::filesystem::path& path) {
  char resolved[PATH_MAX];
  if (::realpath(path.c_str(), resolved) == nullptr) return std::nullopt;
  return std::filesystem::path(resolved);
}

bool IsInside(const std::filesystem::path& root, const std::filesystem::path& candidate) {
  const std::string r = root.string();
  const std::string c = candidate.string();
  return c == r || (c.size() > r.size() && c.compare(0, r.size(), r) == 0 && c[r.size()] == '/');
}

HttpResponse NotFound() {
  return ProblemResponse(404, "no such page");
}

}  // namespace

StaticFiles::StaticFiles(const std::filesystem::path& root) {
  const auto real = RealPath(root);
  if (!real || !std::filesystem::is_directory(*real)) {
    throw std::invalid_argument("web directory does not exist: " + root.string());
  }
  root_ = *real;
}

bool StaticFiles::IsSafeUrlPath(std::string_view url_path) {
  if (url_path.empty() || url_path.front() != '/' || url_path.size() > kMaxUrlPath) return false;
  // The path arrives percent-decoded; '%' left in it means double encoding ("%252e"): refused,
  // as is anything but plain file-name characters (no backslash, NUL, control or non-ASCII).
  for (char c : url_path) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '/' || c == '.' || c == '-' || c == '_';
    if (!ok) return false;
  }
  // No empty, "." or ".." segments and no hidden files (".git", ".env").
  std::size_t start = 1;
  while (start <= url_path.size()) {
    const std::size_t slash = std::min(url_path.find('/', start), url_path.size());
    const std::string_view segment = url_path.substr(start, slash - start);
    if (!segment.empty() && segment.front() == '.') return false;
    if (segment.empty() && slash != url_path.size()) return false;  // "//"
    start = slash + 1;
  }
  return true;
}

HttpResponse StaticFiles::serve(std::string_view url_path) const {
  if (!IsSafeUrlPath(url_path)) return NotFound();
  std::filesystem::path candidate = root_ / std::filesystem::path(url_path.substr(1));
  std::error_code ec;
  if (std::filesystem::is_directory(candidate, ec)) {
    candidate /= "index.html";
  } else if (candidate.extension().empty() && !std::filesystem::exists(candidate, ec)) {
    // A page named without ".html" (/counter, as people say it) is that page: it was a 404 of
    // problem JSON in the browser. The checks below apply to the file found.
    candidate += ".html";
  }
  const auto real = RealPath(candidate);
  // Symlinks may point anywhere; only what resolves inside the web directory is served.
  if (!real || !IsInside(root_, *real) || !std::filesystem::is_regular_file(*real, ec)) {
    return NotFound();
  }
  const std::uintmax_t size = std::filesystem::file_size(*real, ec);
  if (ec || size > kMaxFileBytes) return NotFound();
  std::ifstream in(*real, std::ios::binary);
  if (!in) return NotFound();
  std::string body((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  HttpResponse response = HttpResponse::Bytes(std::string(MediaTypeFor(*real)), std::move(body));
  response.headers.emplace_back("X-Content-Type-Options", "nosniff");
  response.headers.emplace_back("Cache-Control", "no-cache");
  // The pages act with the token typed into them (retiring a pincode cannot be undone):
  // - another site must not frame them and lead a click onto a button it hides;
  // - text that got into a page (an office name from an imported file) must not run as script or
  //   style: only the server's own files run, and pictures come from it or from the photo and label
  //   the page holds (blob:).
  response.headers.emplace_back("Content-Security-Policy", std::string(kPagePolicy));
  response.headers.emplace_back("X-Frame-Options", "SAMEORIGIN");
  return response;
}

std::string_view MediaTypeFor(const std::filesystem::path& path) {
  static constexpr std::array<std::pair<std::string_view, std::string_view>, 14> kTypes = {{
      {".html", "text/html; charset=utf-8"},
      {".htm", "text/html; charset=utf-8"},
      {".js", "text/javascript; charset=utf-8"},
      {".mjs", "text/javascript; charset=utf-8"},
      {".css", "text/css; charset=utf-8"},
      {".json", "application/json"},
      {".svg", "image/svg+xml"},
      {".png", "image/png"},
      {".jpg", "image/jpeg"},
      {".jpeg", "image/jpeg"},
      {".ico", "image/x-icon"},
      {".txt", "text/plain; charset=utf-8"},
      {".webmanifest", "application/manifest+json"},
      {".woff2", "font/woff2"},
  }};
  const std::string ext = path.extension().string();
  for (const auto& [suffix, type] : kTypes) {
    if (ext == suffix) return type;
  }
  return "application/octet-stream";
}

}  // namespace pintag::server
