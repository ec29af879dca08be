#include "pintag/db/scan_log.hpp"

#include "guard.hpp"
#include "pintag/db/text.hpp"

namespace pintag::db {

Result<Connection> OpenScanLogFile(const std::string& path) {
  return detail::Guard([&]() -> Result<Connection> {
    Connection connection(path);
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
  if (scan.result_json.size() > kMaxJsonBytes) {
    return Error{ErrorCode::kInvalid, "scan result JSON is over 1 MiB"};
  }
  if (scan.result_json.find('\0') != std::string::npos) {
    return Error{ErrorCode::kInvalid, "scan result JSON contains a NUL byte"};
  }
  if (scan.image_bytes < 0) return Error{ErrorCode::kInvalid, "image size is negative"};
  return detail::Guard([&]() -> Result<std::int64_t> {
    connection
        .prepare(std::string("INSERT INTO scan_log (scanned_at, token_id, image_bytes, "
                             "image_width, image_height, result_json) VALUES (") +
                 detail::kNowSql + ", ?1, ?2, ?3, ?4, ?5)")
        .bind(1, scan.token_id)
        .bind(2, scan.image_bytes)
        .bind(3, scan.image_width)
        .bind(4, scan.image_height)
        .bind(5, scan.result_json)
        .run();
    return connection.lastInsertRowid();
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
