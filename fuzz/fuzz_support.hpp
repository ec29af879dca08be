#pragma once
// What several fuzz targets share: a seeded registry in a temporary file, made once per fuzzing
// process, with one token per role, and the real application over it; the database put back as
// it was before each input; the check that the seeds meant to succeed still do.

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "pintag/db/sqlite.hpp"
#include "pintag/server/api.hpp"

namespace pintag::fuzz {

struct FuzzRegistry {
  std::string db_path;  ///< a seeded, migrated database in a fresh temporary directory
  std::string admin_token, counter_token, scanner_token;
  std::shared_ptr<const server::Api> api;  ///< app::BuildApi over db_path, as `pintag serve`
};

/// Made on first call (seeding takes a second or two), then the same for the whole process.
const FuzzRegistry& Registry();

/// Puts a database file back, before each input, to the state it had when this was made. One
/// input's writes (a revoked token, a retired pincode, a logged scan) would otherwise change every
/// later answer, and a failure that needed them would not replay from its saved input.
class DatabaseReset {
 public:
  /// Copies the database at `path` into memory.
  explicit DatabaseReset(const std::string& path);
  /// Copies it back with SQLite's backup API when any connection has committed to the file
  /// since the last call (PRAGMA data_version), so that an input that wrote nothing costs one
  /// query instead of a copy of the whole registry; one that only logged scans has their rows
  /// deleted instead.
  void operator()();

 private:
  db::Connection live_;
  db::Connection saved_;
  std::int64_t version_ = 0;           ///< PRAGMA data_version after the last reset
  std::int64_t registry_version_ = 0;  ///< the registry version when saved
  std::int64_t scans_ = 0;             ///< scan log rows when saved
  std::int64_t last_scan_ = 0;         ///< their largest id
};

/// Registry()'s database put back as it was made (DatabaseReset). Call at the start of each input,
/// and once before the first (LLVMFuzzerInitialize) so that the copy is of the fresh registry.
void ResetRegistry();

/// Whether PINTAG_FUZZ_EXPECT_SUCCESS is set: scripts/fuzz.sh then runs the seeds listed in
/// fuzz/expect-success.txt, and a target aborts on any input it does not answer with success
/// (a 2xx, an applied import), so a seed that stops reaching its handler fails the run.
bool ExpectSuccess();

/// Removes `dir` and what it holds when the process exits normally (a fuzz registry is about
/// 34 MB); a crash leaves it, beside the reproducer.
void RemoveDirectoryAtExit(const std::string& dir);

/// `text` with @ADMIN@, @COUNTER@ and @SCANNER@ replaced by those tokens' secrets, so seeds
/// reach the handlers behind auth and mutations of them reach the auth checks.
std::string WithTokens(std::string text);

/// The value of a header in an answer's head, matched at a line's start in cpp-httplib's spelling
/// (an echoed header value may hold the same words), or empty.
std::string_view HeaderValue(std::string_view head, std::string_view name);

/// Aborts unless `answer` starts with one well-formed HTTP/1.1 response whose head is complete:
/// a status of 100 … 599 and not 500 (an unexpected exception or storage failure), an error's
/// Content-Type problem+json, and a 2xx when ExpectSuccess(). With `only_answer` (the bytes after
/// the head are its body, none other) an error without a Content-Type must have no body. Returns
/// the length of the head, its blank line included.
std::size_t CheckHttpAnswer(std::string_view answer, bool only_answer);

}  // namespace pintag::fuzz
