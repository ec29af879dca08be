#pragma once
// The scan log: one row per photo the server decoded, with what was read as JSON text.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "pintag/db/result.hpp"
#include "pintag/db/sqlite.hpp"

namespace pintag::db {

struct ScanRecord {
  std::int64_t id = 0;  ///< assigned on append; ignored on input
  /// ISO 8601 UTC with milliseconds, as ScanTime writes it; when empty, the time of the append.
  std::string scanned_at;
  std::optional<std::int64_t> token_id;  ///< the token that uploaded it, if any
  std::int64_t image_bytes = 0;          ///< size of the uploaded file
  std::optional<int> image_width;        ///< pixels, when decoded
  std::optional<int> image_height;
  std::string result_json;  ///< what was read; must be valid JSON (checked), at most 1 MiB
};

/// A scan log of its own in the file `path`, created when missing. A read-only replica appends
/// here: its registry is a snapshot that is replaced whole and opened read-only. `token_id` then
/// names a token of the snapshot the request was verified against, without a foreign key. A file
/// holding other tables (a registry snapshot, given by mistake) is kConflict and left unchanged.
Result<Connection> OpenScanLogFile(const std::string& path);

/// `when` as the scan log writes it: "2026-12-06T16:20:01.123Z".
std::string ScanTime(std::chrono::system_clock::time_point when);

/// Appends a scan; returns its id. kInvalid for bad JSON, an unknown token id or a scanned_at
/// not in ScanTime's form.
Result<std::int64_t> AppendScan(Connection& connection, const ScanRecord& scan);

/// What AppendScans did with a batch.
struct AppendedScans {
  struct Refusal {
    std::size_t index = 0;  ///< the scan's place in the batch
    Error error;            ///< AppendScan's kInvalid
  };
  std::size_t written = 0;
  std::vector<Refusal> refused;  ///< the scans left out, in order
};

/// Appends `scans` in order in one transaction: every valid one, or none when the database
/// cannot be locked or written (the error: kBusy after the busy timeout, kStorage, kNoSpace).
/// A scan AppendScan would refuse is left out and its error listed; the others are written.
Result<AppendedScans> AppendScans(Connection& connection, std::span<const ScanRecord> scans);
/// Removes the scans taken before `before` (ScanTime's form, or a date "YYYY-MM-DD": its midnight
/// UTC); how many. Found in one pass in id order without a write lock, removed `batch` at a time
/// each in a transaction of its own, so a server writing its scan log waits for one batch at
/// most, never for the whole. The file keeps its size: later scans reuse the room. kInvalid for a
/// `before` in neither form or a `batch` of 0.
Result<std::uint64_t> PruneScans(Connection& connection, std::string_view before,
                                 std::size_t batch = 5000);

/// The newest scans first; `limit` 1–1000; only that token's when `token_id` is given.
Result<std::vector<ScanRecord>> RecentScans(Connection& connection, int limit = 50,
                                            std::optional<std::int64_t> token_id = std::nullopt);

}  // namespace pintag::db
