#pragma once
// The scan log: one row per photo the server decoded, with what was read as JSON text.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "pintag/db/result.hpp"
#include "pintag/db/sqlite.hpp"

namespace pintag::db {

struct ScanRecord {
  std::int64_t id = 0;                   ///< assigned on append; ignored on input
  std::string scanned_at;                ///< ISO 8601 UTC, assigned on append; ignored on input
  std::optional<std::int64_t> token_id;  ///< the token that uploaded it, if any
  std::int64_t image_bytes = 0;          ///< size of the uploaded file
  std::optional<int> image_width;        ///< pixels, when decoded
  std::optional<int> image_height;
  std::string result_json;  ///< what was read; must be valid JSON (checked), at most 1 MiB
};

/// A scan log of its own in the file `path`, created when missing. A read-only replica appends
/// here: its registry is a snapshot that is replaced whole and opened read-only. `token_id` then
/// names a token of the snapshot the request was verified against, without a foreign key.
Result<Connection> OpenScanLogFile(const std::string& path);

/// Appends a scan; returns its id. kInvalid for bad JSON or an unknown token id.
Result<std::int64_t> AppendScan(Connection& connection, const ScanRecord& scan);
/// The newest scans first; `limit` 1–1000; only that token's when `token_id` is given.
Result<std::vector<ScanRecord>> RecentScans(Connection& connection, int limit = 50,
                                            std::optional<std::int64_t> token_id = std::nullopt);

}  // namespace pintag::db
