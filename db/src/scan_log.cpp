#include "pintag/db/scan_log.hpp"

#include <cstdio>
#include <ctime>
#include <string_view>

#include "guard.hpp"
#include "pintag/codec/utf8.hpp"
#include "pintag/db/text.hpp"

namespace pintag::db {
namespace {

/// Whether `text` is written in `form`, where 'd' stands for any digit and every other character
/// for itself.
bool HasForm(std::string_view text, std::string_view form) {
  if (text.size() != form.size()) return false;
  for (std::size_t i = 0; i < form.size(); ++i) {
    const bool ok = form[i] == 'd' ? (text[i] >= '0' && text[i] <= '9') : text[i] == form[i];
    if (!ok) return false;
  }
  return true;
}

// ScanTime's form, digit for digit: "2026-12-06T16:20:01.123Z".
bool IsScanTime(std::string_view text) {
  return HasForm(text, "dddd-dd-ddTdd:dd:dd.dddZ");
}

bool IsDate(std::string_view text) {
  return HasForm(text, "dddd-dd-dd");
}

std::optional<Error> CheckScan(const ScanRecord& scan) {
  if (scan.result_json.size() > kMaxJsonBytes) {
    return Error{ErrorCode::kInvalid, "scan result JSON is over 1 MiB"};
  }
  if (scan.result_json.find('\0') != std::string::npos) {
    return Error{ErrorCode::kInvalid, "scan result JSON contains a NUL byte"};
  }
  if (scan.image_bytes < 0) return Error{ErrorCode::kInvalid, "image size is negative"};
  if (!scan.scanned_at.empty() && !IsScanTime(scan.scanned_at)) {
    return Error{ErrorCode::kInvalid, "scan time is not YYYY-MM-DDTHH:MM:SS.mmmZ"};
  }
  return std::nullopt;
}

// Throws SqliteError; the statement alone fails on a constraint (bad JSON, unknown token).
std::int64_t InsertScan(Connection& connection, const ScanRecord& scan) {
  connection
      .prepare(std::string("INSERT INTO scan_log (scanned_at, token_id, image_bytes, image_width, "
                           "image_height, result_json) VALUES (coalesce(?6, ") +
               detail::kNowSql + "), ?1, ?2, ?3, ?4, ?5)")
      .bind(1, scan.token_id)
      .bind(2, scan.image_bytes)
      .bind(3, scan.image_width)
      .bind(4, scan.image_height)
      .bind(5, scan.result_json)
      .bind(6, scan.scanned_at.empty() ? std::nullopt : std::optional<std::string>(scan.scanned_at))
      .run();
  return connection.lastInsertRowid();
}

}  // namespace

std::string ScanTime(std::chrono::system_clock::time_point when) {
  const auto since_epoch =
      std::chrono::duration_cast<std::chrono::milliseconds>(when.time_since_epoch()).count();
  const std::time_t seconds = static_cast<std::time_t>(since_epoch / 1000);
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char text[64];  // room for any int the compiler can imagine in each field
  std::snprintf(text, sizeof text, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", utc.tm_year + 1900,
                utc.tm_mon + 1, utc.tm_mday, utc.tm_hour, utc.tm_min, utc.tm_sec,
                static_cast<int>(since_epoch % 1000));
  return text;
}

Result<Connection> OpenScanLogFile(const std::string& path) {
  return detail::Guard([&]() -> Result<Connection> {
    // Not switched to WAL before it is known to be a scan log: a registry snapshot given by
    // mistake (a replica's own --db, another replica's file) would be written over in place.
    Connection connection(path, {.wal = false});
    std::string others;
    Statement tables = connection.prepare(
        "SELECT name FROM sqlite_schema WHERE type = 'table' AND name <> 'scan_log' AND name NOT "
        "LIKE 'sqlite\\_%' ESCAPE '\\' ORDER BY name");
    for (int shown = 0; shown < 3 && tables.step(); ++shown) {
      others += (others.empty() ? "" : ", ") + tables.getText(0);
    }
    if (!others.empty()) {
      return Error{ErrorCode::kConflict,
                   "the file holds other tables (" + others +
                       "), so it is not a scan log (a registry snapshot or database?); give the "
                       "scan log a file of its own, which is created when missing"};
    }
    connection.execute("PRAGMA journal_mode=WAL");
    // The columns of the registry's scan_log (migration 2), so AppendScan and RecentScans work
    // on either.
    connection.execute(R"sql(
CREATE TABLE IF NOT EXISTS scan_log (
  id           INTEGER PRIMARY KEY,
  scanned_at   TEXT NOT NULL,
  token_id     INTEGER,
  image_bytes  INTEGER NOT NULL CHECK (image_bytes >= 0),
  image_width  INTEGER,
  image_height INTEGER,
  result_json  TEXT NOT NULL CHECK (json_valid(result_json))
);
CREATE INDEX IF NOT EXISTS scan_log_token ON scan_log (token_id, id);
)sql");
    return connection;
  });
}

Result<std::int64_t> AppendScan(Connection& connection, const ScanRecord& scan) {
  if (auto refused = CheckScan(scan)) return *refused;
  return detail::Guard([&]() -> Result<std::int64_t> { return InsertScan(connection, scan); });
}

Result<AppendedScans> AppendScans(Connection& connection, std::span<const ScanRecord> scans) {
  return detail::Guard([&]() -> Result<AppendedScans> {
    AppendedScans appended;
    Transaction transaction(connection);
    for (std::size_t i = 0; i < scans.size(); ++i) {
      if (auto refused = CheckScan(scans[i])) {
        appended.refused.push_back({i, std::move(*refused)});
        continue;
      }
      try {
        InsertScan(connection, scans[i]);
        ++appended.written;
      } catch (const SqliteError& e) {
        if (!e.isConstraint()) throw;  // the whole batch: nothing is committed
        appended.refused.push_back({i, detail::ToError(e)});
      }
    }
    transaction.commit();
    return appended;
  });
}

Result<std::uint64_t> PruneScans(Connection& connection, std::string_view before,
                                 std::size_t batch) {
  std::string cutoff(before);
  if (IsDate(before)) {
    cutoff += "T00:00:00.000Z";
  } else if (!IsScanTime(before)) {
    return Error{ErrorCode::kInvalid, QuotedPrefix(before, 40) +
                                          " is not a date (YYYY-MM-DD) or a scan time "
                                          "(YYYY-MM-DDTHH:MM:SS.mmmZ)"};
  }
  if (batch == 0) return Error{ErrorCode::kInvalid, "a batch removes at least one scan"};
  return detail::Guard([&]() -> Result<std::uint64_t> {
    // Scan times follow ids closely but not exactly (a batch of scans is written at once), so
    // each removal is bounded by ids and still asks for the time.
    Statement find = connection.prepare(
        "SELECT min(id), max(id), count(*) FROM (SELECT id FROM scan_log WHERE id > ?1 AND "
        "scanned_at < ?2 ORDER BY id LIMIT ?3)");
    Statement remove =
        connection.prepare("DELETE FROM scan_log WHERE id BETWEEN ?1 AND ?2 AND scanned_at < ?3");
    std::uint64_t removed = 0;
    std::int64_t after = 0;  // ids start at 1
    for (;;) {
      find.reset();
      find.bind(1, after).bind(2, cutoff).bind(3, static_cast<std::int64_t>(batch));
      if (!find.step() || find.getInt64(2) == 0) break;
      const std::int64_t first = find.getInt64(0);
      const std::int64_t last = find.getInt64(1);
      find.reset();  // its read ends before the batch's write begins
      Transaction transaction(connection);
      remove.reset();
      removed +=
          static_cast<std::uint64_t>(remove.bind(1, first).bind(2, last).bind(3, cutoff).run());
      transaction.commit();
      after = last;
    }
    return removed;
  });
}

Result<std::vector<ScanRecord>> RecentScans(Connection& connection, int limit,
                                            std::optional<std::int64_t> token_id) {
  if (limit < 1 || limit > 1000) return Error{ErrorCode::kInvalid, "limit must be 1 to 1000"};
  return detail::Guard([&]() -> Result<std::vector<ScanRecord>> {
    Statement s = connection.prepare(
        "SELECT id, scanned_at, token_id, image_bytes, image_width, image_height, result_json "
        "FROM scan_log WHERE (?1 IS NULL OR token_id = ?1) ORDER BY id DESC LIMIT ?2");
    s.bind(1, token_id).bind(2, limit);
    std::vector<ScanRecord> scans;
    while (s.step()) {
      ScanRecord scan;
      scan.id = s.getInt64(0);
      scan.scanned_at = s.getText(1);
      if (!s.isNull(2)) scan.token_id = s.getInt64(2);
      scan.image_bytes = s.getInt64(3);
      if (!s.isNull(4)) scan.image_width = s.getInt(4);
      if (!s.isNull(5)) scan.image_height = s.getInt(5);
      scan.result_json = s.getText(6);
      scans.push_back(std::move(scan));
    }
    return scans;
  });
}

}  // namespace pintag::db
