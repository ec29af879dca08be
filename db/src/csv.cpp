#include "pintag/db/csv.hpp"

#include <string>

namespace pintag::db {

CsvReader::CsvReader(std::string_view text) : text_(text) {
  if (text_.starts_with("\xEF\xBB\xBF")) position_ = 3;
}

bool CsvReader::endsLine(std::size_t at) const {
  return text_[at] == '\n' ||
         (text_[at] == '\r' && (at + 1 == text_.size() || text_[at + 1] != '\n'));
}

std::optional<CsvRecord> CsvReader::next(std::string* error) {
  error->clear();
  // Blank lines between records are skipped (a trailing newline must not make an empty record).
  while (position_ < text_.size() && (text_[position_] == '\n' || text_[position_] == '\r')) {
    if (endsLine(position_)) ++line_;
    ++position_;
  }
  if (position_ >= text_.size()) return std::nullopt;
  CsvRecord record;
  record.line = line_;
  std::string field;
  bool quoted = false;      // inside a quoted field
  bool was_quoted = false;  // the current field started with a quote
  const auto fail = [&](const std::string& why) {
    if (error->empty()) *error = why;
  };
  // Fields past the limit are read over, not kept: a line of 25 million commas held a string for
  // each (1.1 GB) before its field count was checked.
  const auto keep = [&](std::string&& done) {
    if (record.fields.size() < kMaxCsvFields) {
      record.fields.push_back(std::move(done));
    } else {
      fail("more than " + std::to_string(kMaxCsvFields) + " fields");
    }
  };
  while (position_ < text_.size()) {
    const char c = text_[position_++];
    if (quoted) {
      if (c == '"') {
        if (position_ < text_.size() && text_[position_] == '"') {
          field += '"';
          ++position_;
        } else {
          quoted = false;
        }
      } else {
        if (endsLine(position_ - 1)) {
          if (record.line_break_quote_line == 0) record.line_break_quote_line = record.quote_line;
          ++line_;
        }
        field += c;
      }
      continue;
    }
    if (c == ',') {
      keep(std::move(field));
      field.clear();
      was_quoted = false;
    } else if (c == '\n' || c == '\r') {
      if (c == '\r' && position_ < text_.size() && text_[position_] == '\n') ++position_;
      record.last_line = line_;
      ++line_;
      keep(std::move(field));
      return record;
    } else if (c == '"') {
      // Spaces before the opening quote are dropped, as a hand-written `11, "delhi, north"` means.
      if (!was_quoted && field.find_first_not_of(' ') == std::string::npos) {
        field.clear();
        quoted = was_quoted = true;
        record.quote_line = line_;
      } else {
        fail("stray double quote");
        field += c;
      }
    } else if (was_quoted) {
      if (c != ' ') fail("text after a closing quote");  // spaces after it are dropped
    } else {
      field += c;
    }
  }
  // Overrides an earlier fault of the record: the rest of the file has gone into this field.
  if (quoted) *error = kUnterminatedQuote;
  record.last_line = line_;
  keep(std::move(field));
  return record;
}

std::string CsvField(std::string_view text) {
  // A semicolon too: spreadsheets in much of Europe split cells at it, and a bin "a;=1+1" left
  // bare became a cell "=1+1", run as a formula. Quoted, it stays one cell.
  if (text.find_first_of(",;\"\r\n") == std::string_view::npos) return std::string(text);
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

std::string CsvTextField(std::string_view text) {
  if (!text.empty() && std::string_view("=+-@\t\r").find(text.front()) != std::string_view::npos) {
    // Appended, not `"'" + ...`: GCC 12 warns (-Wrestrict) about that concatenation wrongly.
    std::string guarded = "'";
    guarded += text;
    return CsvField(guarded);
  }
  return CsvField(text);
}

}  // namespace pintag::db
