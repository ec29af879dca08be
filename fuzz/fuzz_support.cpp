#include "fuzz_support.hpp"

#include <stdlib.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <vector>

#include "app/app.hpp"
#include "pintag/db/database.hpp"
#include "pintag/db/tokens.hpp"
#include "pintag/server/log.hpp"

namespace pintag::fuzz {
namespace {

std::int64_t RegistryVersionOf(db::Connection& connection) {
  return connection.queryInt64("SELECT version FROM registry_version");
}

std::int64_t ScanCount(db::Connection& connection) {
  return connection.queryInt64("SELECT count(*) FROM scan_log");
}

FuzzRegistry Make() {
  std::string dir = (std::filesystem::temp_directory_path() / "pintag-fuzz-XXXXXX").string();
  if (::mkdtemp(dir.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
  RemoveDirectoryAtExit(dir);
  FuzzRegistry registry;
  registry.db_path = dir + "/registry.db";
  auto opened = db::OpenDatabase(registry.db_path);
  if (!opened) throw std::runtime_error(opened.error().message);
  auto& connection = opened.value().connection;
  const auto token = [&](db::Role role) {
    auto made = db::CreateToken(connection, role, "fuzz");
    if (!made) throw std::runtime_error(made.error().message);
    return made->secret;
  };
  registry.admin_token = token(db::Role::kAdmin);
  registry.counter_token = token(db::Role::kCounter);
  registry.scanner_token = token(db::Role::kScanner);
  // Token 4, for the revoke seed: revoking token 1 (the admin's) locked every later input out of
  // the admin routes for the rest of a campaign.
  token(db::Role::kScanner);
  // A web directory, so that static files are served too (a page and a script, and a folder
  // whose index.html is served for its bare path).
  std::filesystem::create_directories(dir + "/web/docs");
  std::ofstream(dir + "/web/index.html") << "<!doctype html><title>PinTag</title>\n";
  std::ofstream(dir + "/web/app.js") << "export const ready = true;\n";
  std::ofstream(dir + "/web/docs/index.html") << "<!doctype html><title>docs</title>\n";
  app::AppConfig config;
  config.db_path = registry.db_path;
  config.web_dir = dir + "/web";
  config.max_pixels = 1 << 20;  // small photos keep executions fast; limits are tested elsewhere
  config.max_batch = 4;
  config.max_tag_px = 256;
  registry.api = app::BuildApi(config);
  return registry;
}

void ReplaceAll(std::string& text, std::string_view from, const std::string& to) {
  for (std::size_t at = text.find(from); at != std::string::npos; at = text.find(from, at)) {
    text.replace(at, from.size(), to);
    at += to.size();
  }
}

}  // namespace

void RemoveDirectoryAtExit(const std::string& dir) {
  static std::vector<std::string> dirs;
  if (dirs.empty()) {
    std::atexit([] {
      std::error_code ignored;
      for (const std::string& d : dirs) std::filesystem::remove_all(d, ignored);
    });
  }
  dirs.push_back(dir);
}

const FuzzRegistry& Registry() {
  static const FuzzRegistry registry = Make();
  return registry;
}

DatabaseReset::DatabaseReset(const std::string& path)
    : live_(path, {.create = false}), saved_(":memory:", {.wal = false}) {
  live_.backupInto(saved_);
  registry_version_ = RegistryVersionOf(live_);
  scans_ = ScanCount(live_);
  last_scan_ = live_.queryInt64("SELECT coalesce(max(id), 0) FROM scan_log");
  version_ = live_.queryInt64("PRAGMA data_version");
}

void DatabaseReset::operator()() {
  // data_version changes only with other connections' commits: the server's pool, the scan log
  // writer, the importer's; never with this connection's own restore.
  const std::int64_t version = live_.queryInt64("PRAGMA data_version");
  if (version == version_) return;
  // Every table but the scan log bumps the registry version when written. An input that only
  // logged scans (most /detect uploads) is undone by deleting their rows, as the copy would
  // leave it (its ids are reused: no AUTOINCREMENT); the copy of the whole registry cost ten
  // times the executions a second.
  bool undone = false;
  if (RegistryVersionOf(live_) == registry_version_) {
    live_.execute("DELETE FROM scan_log WHERE id > " + std::to_string(last_scan_));
    undone = ScanCount(live_) == scans_;
  }
  if (!undone) saved_.backupInto(live_);
  version_ = live_.queryInt64("PRAGMA data_version");
}

void ResetRegistry() {
  static DatabaseReset reset(Registry().db_path);
  reset();
}

bool ExpectSuccess() {
  static const bool expect = std::getenv("PINTAG_FUZZ_EXPECT_SUCCESS") != nullptr;
  return expect;
}

std::string_view HeaderValue(std::string_view head, std::string_view name) {
  const std::string key = "\r\n" + std::string(name) + ": ";
  const std::size_t at = head.find(key);
  if (at == std::string_view::npos) return {};
  const std::size_t from = at + key.size();
  return head.substr(from, head.find("\r\n", from) - from);
}

std::size_t CheckHttpAnswer(std::string_view answer, bool only_answer) {
  const auto fail = [&](const char* why) {
    std::fprintf(stderr, "%s:\n%.600s\n", why, std::string(answer.substr(0, 600)).c_str());
    std::abort();
  };
  if (answer.rfind("HTTP/1.1 ", 0) != 0) fail("not an HTTP/1.1 response");
  const std::size_t head_end = answer.find("\r\n\r\n");
  if (head_end == std::string_view::npos) fail("a response head without its end");
  const int status = std::atoi(std::string(answer.substr(9, 3)).c_str());
  if (status < 100 || status > 599) fail("a status out of range");
  if (status == 500) fail("answered 500");
  if (status >= 400) {
    const std::string_view type = HeaderValue(answer.substr(0, head_end + 2), "Content-Type");
    const bool has_body = answer.size() > head_end + 4;
    if (type.empty() ? only_answer && has_body : type != "application/problem+json") {
      fail("error answered without problem+json");
    }
  }
  if (ExpectSuccess() && (status < 200 || status > 299)) fail("expected a 2xx");
  return head_end + 4;
}

std::string WithTokens(std::string text) {
  const FuzzRegistry& r = Registry();
  ReplaceAll(text, "@ADMIN@", r.admin_token);
  ReplaceAll(text, "@COUNTER@", r.counter_token);
  ReplaceAll(text, "@SCANNER@", r.scanner_token);
  return text;
}

}  // namespace pintag::fuzz
