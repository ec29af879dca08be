#pragma once
// RFC 4180 CSV reading: comma-separated, fields optionally in double quotes ("" inside quotes is
// one quote; quoted fields may hold commas and line breaks), CRLF, LF or CR line ends (each counts
// one line), a leading UTF-8 byte-order mark skipped.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace pintag::db {

struct CsvRecord {
  std::int64_t line = 0;  ///< 1-based line on which the record starts
  /// The line it ends on: later than `line` when a quoted field holds line breaks.
  std::int64_t last_line = 0;
  std::int64_t quote_line = 0;  ///< the line where its last quoted field opened (0: none)
  /// The line where the first quoted field holding a line break opened (0: none).
  std::int64_t line_break_quote_line = 0;
  std::vector<std::string> fields;
};

/// Fields kept of one record; a record with more is read to its end and has an error (the
/// layouts read here have at most a few dozen columns).
inline constexpr std::size_t kMaxCsvFields = 256;

/// The error of a record whose quoted field is never closed: it has read to the end of the text.
inline constexpr std::string_view kUnterminatedQuote = "unterminated quoted field";

class CsvReader {
 public:
  explicit CsvReader(std::string_view text);

  /// The next record; nothing at the end. A malformed record (a quote inside an unquoted field,
  /// text after a closing quote, an unterminated quote) sets `error` and is returned as far as
  /// it was read; reading continues on the next line.
  std::optional<CsvRecord> next(std::string* error);
  std::size_t position() const { return position_; }  ///< bytes consumed so far

 private:
  bool endsLine(std::size_t at) const;  ///< LF, or a CR not followed by LF

  std::string_view text_;
  std::size_t position_ = 0;
  std::int64_t line_ = 1;
};

/// Quotes a field when it holds a comma, semicolon (a list separator in many locales'
/// spreadsheets), quote, CR or LF.
std::string CsvField(std::string_view text);

/// CsvField for free text in a file that is only read, never imported again (the token list): a
/// field starting with = + - @ or a tab gets a leading ' so that a spreadsheet shows it as text
/// instead of running it as a formula. Not for the sort plan CSV, which is put back as it reads.
std::string CsvTextField(std::string_view text);

}  // namespace pintag::db
