#pragma once
// What several fuzz targets share: a seeded registry in a temporary file, made once per fuzzing
// process, with one token per role, and the real application over it.

#include <memory>
#include <string>

#include "pintag/server/api.hpp"

namespace pintag::fuzz {

struct FuzzRegistry {
  std::string db_path;  ///< a seeded, migrated database in a fresh temporary directory
  std::string admin_token, counter_token, scanner_token;
  std::shared_ptr<const server::Api> api;  ///< app::BuildApi over db_path, as `pintag serve`
};

/// Made on first call (seeding takes a second or two), then the same for the whole process.
const FuzzRegistry& Registry();

/// Removes `dir` and what it holds when the process exits normally (a fuzz registry is about
/// 34 MB); a crash leaves it, beside the reproducer.
void RemoveDirectoryAtExit(const std::string& dir);

/// `text` with @ADMIN@, @COUNTER@ and @SCANNER@ replaced by those tokens' secrets, so seeds
/// reach the handlers behind auth and mutations of them reach the auth checks.
std::string WithTokens(std::string text);

}  // namespace pintag::fuzz
