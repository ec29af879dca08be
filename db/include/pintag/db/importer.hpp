#pragma once
// Importing India Post's "All India Pincode Directory" CSV. Both published layouts, told apart by
// the header (column names compared case-insensitively, in any order):
//   newer:  circlename,regionname,divisionname,officename,pincode,officetype,delivery,district,
//           statename,latitude,longitude
//   older:  officename,pincode,officeType,Deliverystatus,divisionname,regionname,circlename,
//           Taluk,Districtname,statename
// An office is identified by (pincode, office name); re-importing a file changes nothing. A
// trailing " B.O"/" S.O"/" H.O" (or "BO"...) matching the office type is dropped from the name
// (" S.O" of a PO too: the newer layout types sub offices PO), so India Post rows match the seed's
// names and fill in their branch type ("B.O" is stored "BO").
// New pincodes get new keys (probing past every key ever allocated, retired ones included);
// existing keys never change; a retired pincode stays retired. The whole import is one transaction.

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "pintag/codec/pincode.hpp"
#include "pintag/codec/tag_key.hpp"
#include "pintag/db/registry.hpp"
#include "pintag/db/result.hpp"
#include "pintag/db/sqlite.hpp"

namespace pintag::db {

enum class CsvLayout { kNewer, kOlder };
const char* ToString(
    CsvLayout layout);  ///< "newer (with latitude/longitude)", "older (with taluk)"

/// Called now and then while importing: the phase ("parse" or "write"), units done and total
/// (bytes while parsing, rows while writing).
using ImportProgress =
    std::function<void(std::string_view phase, std::uint64_t done, std::uint64_t total)>;

struct ImportOptions {
  bool strict = false;      ///< any bad row refuses the whole import (default: skip bad rows)
  std::string source;       ///< recorded in rows' `source` column; default "import:<layout>"
  ImportProgress progress;  ///< may be empty
};

struct RowProblem {
  std::int64_t line = 0;  ///< 1-based line where the CSV record starts (the header is line 1)
  std::string message;
};

struct ImportReport {
  CsvLayout layout = CsvLayout::kNewer;
  bool applied = false;   ///< false when --strict refused it (the database is unchanged)
  std::int64_t rows = 0;  ///< data records read
  std::int64_t offices_added = 0;
  std::int64_t offices_updated = 0;
  std::int64_t offices_unchanged = 0;
  std::int64_t repeated_rows = 0;  ///< rows the same as an earlier one of the file, skipped
  std::vector<std::pair<Pincode, TagKey>> pincodes_added;  ///< with their new keys
  std::int64_t bad_rows = 0;  ///< every bad row, skipped or (strict) refusing the file
  /// The first kMaxProblemsKept bad rows, in file order: a file of ten million bad lines must not
  /// hold ten million messages (one test file of 20 MB took 1.2 GB for them).
  std::vector<RowProblem> problems;
};

/// How many bad rows an ImportReport describes one by one; ImportReport::bad_rows counts them all.
inline constexpr std::size_t kMaxProblemsKept = 1000;

/// One office of a parsed file, checked and ready to write.
struct ImportRow {
  std::int64_t line = 0;  ///< where its record starts, as RowProblem::line
  Pincode pincode{100000};
  PostOffice office;
};

/// A file read and checked, nothing written: its layout, row counts and bad rows in `report`
/// (`applied` false, no new pincodes yet) and the offices to write.
struct ParsedImport {
  ImportReport report;
  std::vector<ImportRow> rows;
};

/// The first half of ImportDirectoryCsv, which touches no database: a caller can refuse a bad
/// file (kInvalid, as below) or one whose rows are all bad before it opens or creates one.
Result<ParsedImport> ParseDirectoryCsv(std::string_view csv, const ImportOptions& options = {});
/// The second half: writes a parsed file in one transaction; with `options.strict` and bad rows,
/// nothing (the report's `applied` false). Errors as ImportDirectoryCsv's from SQLite and keys.
Result<ImportReport> ApplyDirectoryCsv(Connection& connection, ParsedImport parsed,
                                       const ImportOptions& options = {});

/// Imports CSV text (ParseDirectoryCsv, then ApplyDirectoryCsv). Errors (nothing applied): kInvalid
/// for an empty file, a header of neither layout (naming the columns it lacks) or with a column
/// twice (naming it), a header and no rows, or a quoted field never closed (the rest of the file
/// is then one field), kFull when the keys run out, kBusy/kStorage from SQLite. Bad rows are
/// reported in the report instead; an office (pincode and name) a second time is a bad row unless
/// the row is the same as the first, which is kept.
Result<ImportReport> ImportDirectoryCsv(Connection& connection, std::string_view csv,
                                        const ImportOptions& options = {});
/// The largest file ReadImportFile reads: India Post's whole directory is about 20 MB.
inline constexpr std::size_t kMaxImportFileBytes = std::size_t{256} << 20;

/// The whole file, read before any database is opened; kNotFound when it cannot be read,
/// kInvalid for a directory, kTooLarge past kMaxImportFileBytes (found as it is read, so a
/// device that never ends, such as /dev/zero, is refused too), kStorage for a read error (the
/// message gives the system's reason).
Result<std::string> ReadImportFile(const std::string& path);
/// As ReadImportFile, from a stream already open (`pintag import -`: standard input, read as it
/// is, from where it stands); `name` names it in messages.
Result<std::string> ReadImportStream(std::istream& in, const std::string& name);
/// Reads the file (ReadImportFile) and imports it.
Result<ImportReport> ImportDirectoryCsvFile(Connection& connection, const std::string& path,
                                            const ImportOptions& options = {});

}  // namespace pintag::db
