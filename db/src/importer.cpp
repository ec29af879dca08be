#include "pintag/db/importer.hpp"

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <span>
#include <sstream>
#include <unordered_set>

#include "guard.hpp"
#include "pintag/codec/utf8.hpp"
#include "pintag/db/csv.hpp"
#include "pintag/db/office_fields.hpp"
#include "pintag/db/text.hpp"
#include "registry_internal.hpp"

namespace pintag::db {
namespace {

constexpr std::int64_t kProgressEvery = 4096;  ///< rows between progress calls

enum Column {
  kOffice,
  kPincode,
  kType,
  kDelivery,
  kDivision,
  kRegion,
  kCircle,
  kDistrict,
  kState,
  kTaluk,
  kLatitude,
  kLongitude,
  kColumnCount
};

/// A header name as India Post publishes it (compared case-insensitively) and what it holds.
struct NamedColumn {
  std::string_view name;
  Column column;
};

constexpr NamedColumn kNewerColumns[] = {
    {"circlename", kCircle}, {"regionname", kRegion},  {"divisionname", kDivision},
    {"officename", kOffice}, {"pincode", kPincode},    {"officetype", kType},
    {"delivery", kDelivery}, {"district", kDistrict},  {"statename", kState},
    {"latitude", kLatitude}, {"longitude", kLongitude}};
constexpr NamedColumn kOlderColumns[] = {{"officename", kOffice},     {"pincode", kPincode},
                                         {"officeType", kType},       {"Deliverystatus", kDelivery},
                                         {"divisionname", kDivision}, {"regionname", kRegion},
                                         {"circlename", kCircle},     {"Taluk", kTaluk},
                                         {"Districtname", kDistrict}, {"statename", kState}};

struct LayoutSpec {
  CsvLayout layout;
  const char* label;                     ///< for messages
  std::span<const NamedColumn> columns;  ///< in the published order
};

constexpr LayoutSpec kLayouts[] = {{CsvLayout::kNewer, "newer", kNewerColumns},
                                   {CsvLayout::kOlder, "older", kOlderColumns}};

std::string Lower(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

/// "a, b and c" (or "a,b,c" with both separators ",").
template <typename Range>
std::string Join(const Range& items, std::string_view separator = ", ",
                 std::string_view last_separator = " and ") {
  std::string out;
  const std::size_t count = std::size(items);
  std::size_t i = 0;
  for (const auto& item : items) {
    if (i > 0) out += i + 1 == count ? last_separator : separator;
    out += item;
    ++i;
  }
  return out;
}

struct Mapping {
  CsvLayout layout;
  std::array<int, kColumnCount> index;  ///< field index per column, -1 when absent
  std::size_t width;
};

/// What a file that cannot be the directory's CSV is, told from its first bytes, or nothing: a
/// UTF-16 export, a compressed file or a workbook otherwise failed as "missing the columns…"
/// or "stray double quote", which did not say what to do.
std::optional<std::string> NotCsvText(std::string_view bytes) {
  const auto starts = [&](std::string_view prefix) { return bytes.starts_with(prefix); };
  if (starts("\xFF\xFE") || starts("\xFE\xFF")) {
    return "the file is UTF-16 text (as Excel's \"Unicode Text\" saves it); save it as "
           "\"CSV UTF-8\" and import that";
  }
  if (starts("\x1F\x8B")) return "the file is compressed (gzip); gunzip it and import the CSV";
  if (starts("PK\x03\x04")) {
    return "the file is a ZIP archive (an .xlsx workbook?); save the sheet as \"CSV UTF-8\" or "
           "unzip it, and import the CSV";
  }
  // UTF-16 without a byte order mark (a NUL in its first line), or an image (a NUL among the
  // first bytes). A NUL in a data row is that row's problem, refused with it (CheckText).
  const std::string_view first_line = bytes.substr(0, bytes.find('\n'));
  if (first_line.find('\0') != std::string_view::npos ||
      bytes.substr(0, 16).find('\0') != std::string_view::npos) {
    return "the file is not text (it holds NUL bytes: UTF-16 without a byte order mark, or a "
           "binary file); give the CSV as UTF-8 text";
  }
  return std::nullopt;
}

/// The layout a header is, or why it is neither: the columns missing from the nearer layout, or
/// one of its columns given twice (which of the two holds the value cannot be told).
Result<Mapping> Detect(const std::vector<std::string>& header) {
  std::map<std::string, std::vector<std::size_t>> fields_named;  // lower-case name -> 1-based
  for (std::size_t i = 0; i < header.size(); ++i) {
    fields_named[Lower(TrimUnicodeSpaces(header[i]))].push_back(i + 1);
  }
  const LayoutSpec* nearest = nullptr;
  std::vector<std::string_view> missing;
  for (const LayoutSpec& spec : kLayouts) {
    std::vector<std::string_view> lacking;
    for (const NamedColumn& column : spec.columns) {
      if (!fields_named.contains(Lower(column.name))) lacking.push_back(column.name);
    }
    if (nearest == nullptr || lacking.size() < missing.size()) {
      nearest = &spec;
      missing = std::move(lacking);
    }
  }
  // One field holding the names with another separator between them: say so, not what is missing.
  if (!missing.empty() && header.size() == 1) {
    for (const auto& [separator, name] : {std::pair{';', "semicolons"}, std::pair{'\t', "tabs"}}) {
      if (header[0].find(separator) != std::string::npos) {
        return Error{ErrorCode::kInvalid,
                     std::string("line 1: the fields are separated by ") + name +
                         ", not commas; save the file as CSV with commas (\"CSV UTF-8\")"};
      }
    }
  }
  if (!missing.empty()) {
    std::string layouts;
    for (const LayoutSpec& spec : kLayouts) {
      std::vector<std::string_view> names;
      names.reserve(spec.columns.size());
      for (const NamedColumn& column : spec.columns) names.push_back(column.name);
      layouts +=
          (layouts.empty() ? "" : "; ") + std::string(spec.label) + ": " + Join(names, ",", ",");
    }
    return Error{ErrorCode::kInvalid,
                 "line 1: not an All India Pincode Directory header: missing the " +
                     std::string(nearest->label) + " layout's " + Join(missing) +
                     " (the layouts' columns, " + layouts + ")"};
  }
  Mapping mapping{nearest->layout, {}, header.size()};
  mapping.index.fill(-1);
  for (const NamedColumn& column : nearest->columns) {
    const std::vector<std::size_t>& fields = fields_named.at(Lower(column.name));
    if (fields.size() > 1) {
      std::vector<std::string> numbers;
      numbers.reserve(fields.size());
      for (const std::size_t field : fields) numbers.push_back(std::to_string(field));
      return Error{ErrorCode::kInvalid,
                   "line 1: the header has the column " + std::string(column.name) + " " +
                       std::to_string(fields.size()) + " times (fields " + Join(numbers) +
                       "); which one holds the value cannot be told"};
    }
    mapping.index[column.column] = static_cast<int>(fields.front() - 1);
  }
  return mapping;
}

/// A decimal number. from_chars refuses a leading '+', which a spreadsheet may write: it is taken
/// before a digit or a point (so "+-5" and "++5" stay bad).
std::optional<double> ParseNumber(std::string_view text) {
  if (text.size() > 1 && text[0] == '+' &&
      (std::isdigit(static_cast<unsigned char>(text[1])) != 0 || text[1] == '.')) {
    text.remove_prefix(1);
  }
  double value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || !std::isfinite(value)) {
    return std::nullopt;
  }
  return value;
}

/// The letters a name's type suffix may have for an office of type "<letter>O": its own, and for
/// PO also S, since the newer layout types sub offices PO but still names them "... SO"/"... S.O".
std::string SuffixLetters(char letter) {
  return letter == 'P' ? "PS" : std::string(1, letter);
}

/// Drops " B.O", " S.O.", " HO" and the like when they repeat the office type's letter (or say
/// S.O of a PO: SuffixLetters).
std::string StripTypeSuffix(std::string name, const std::optional<std::string>& type) {
  if (!type || type->size() != 2 || (type->back() != 'O' && type->back() != 'o')) return name;
  const std::string letters =
      SuffixLetters(static_cast<char>(std::toupper(static_cast<unsigned char>(type->front()))));
  std::string upper = name;
  for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  // Longest first: " X.O.", " X.O", " XO".
  for (const std::string_view pattern :
       {std::string_view(" ?.O."), std::string_view(" ?.O"), std::string_view(" ?O")}) {
    if (upper.size() <= pattern.size()) continue;
    const std::string_view tail = std::string_view(upper).substr(upper.size() - pattern.size());
    bool match = true;
    for (std::size_t i = 0; i < pattern.size(); ++i) {
      match = match && (pattern[i] == '?' ? letters.find(tail[i]) != std::string::npos
                                          : tail[i] == pattern[i]);
    }
    if (match) {
      name.resize(name.size() - pattern.size());
      return std::string(TrimUnicodeSpaces(name));
    }
  }
  return name;
}

/// The seed keeps a type suffix in a few names ("Dumrawan SO", "Khanapur  BO", "Akhodad So": 22 of
/// them), which an import's "Dumrawan S.O" loses: such a stored office, when no office has the
/// stripped name yet, is renamed to it, so the import updates it instead of adding a second office
/// that would become the pincode's main one. True when one was renamed.
bool RenameSuffixedTwin(Connection& connection, Pincode pincode, const PostOffice& office) {
  Statement named =
      connection.prepare("SELECT count(*) FROM offices WHERE pincode = ?1 AND trim(name) = ?2");
  named.bind(1, std::int64_t{pincode.value()}).bind(2, office.name);
  named.step();
  if (named.getInt64(0) > 0) return false;
  std::vector<std::pair<std::int64_t, std::string>> longer;  // id, name
  {
    Statement find = connection.prepare(
        "SELECT id, name FROM offices WHERE pincode = ?1 AND "
        "substr(name, 1, length(?2) + 1) = ?2 || ' ' ORDER BY id");
    find.bind(1, std::int64_t{pincode.value()}).bind(2, office.name);
    while (find.step()) longer.emplace_back(find.getInt64(0), find.getText(1));
  }
  for (const auto& [id, name] : longer) {
    if (StripTypeSuffix(name, office.branch_type) != office.name) continue;
    connection
        .prepare(std::string("UPDATE offices SET name = ?2, updated_at = ") + detail::kNowSql +
                 " WHERE id = ?1")
        .bind(1, id)
        .bind(2, office.name)
        .run();
    return true;
  }
  return false;
}

/// An optional detail the two rows agree on, or that only one of them knows.
template <typename T>
bool Agree(const std::optional<T>& a, const std::optional<T>& b) {
  return !a || !b || *a == *b;
}

/// `later` says nothing against `kept` (its known details are the same, or `kept` lacked them):
/// then what only `later` knows is added to `kept`, as a second import of it would add.
bool MergeRepeat(PostOffice& kept, const PostOffice& later) {
  const bool same = kept.name == later.name && kept.division == later.division &&
                    kept.region == later.region && kept.circle == later.circle &&
                    kept.district == later.district && kept.state == later.state &&
                    Agree(kept.branch_type, later.branch_type) &&
                    Agree(kept.delivery, later.delivery) && Agree(kept.taluk, later.taluk) &&
                    Agree(kept.latitude, later.latitude) && Agree(kept.longitude, later.longitude);
  if (!same) return false;
  const auto fill = [](auto& into, const auto& from) {
    if (!into) into = from;
  };
  fill(kept.branch_type, later.branch_type);
  fill(kept.delivery, later.delivery);
  fill(kept.taluk, later.taluk);
  fill(kept.latitude, later.latitude);
  fill(kept.longitude, later.longitude);
  return true;
}

/// A field's text as a message may quote it: at most 40 bytes (cut at a character), control bytes
/// and the code points CheckText refuses (a bidi override would reorder the line) written as
/// \xNN. A coordinate field of a megabyte, or one holding a terminal's escape
/// sequences, would otherwise be printed as it is.
std::string ShownField(std::string_view text) {
  constexpr std::size_t kMaxShown = 40;
  std::string shown;
  std::size_t i = 0;
  while (i < text.size() && i < kMaxShown) {
    const Utf8CodePoint decoded = DecodeUtf8(text, i);
    const bool control = decoded.length == 0 || decoded.value < 0x20 || decoded.value == 0x7F ||
                         RefusedCodePoint(decoded.value) != nullptr;
    const std::size_t length = decoded.length == 0 ? 1 : decoded.length;
    if (control) {
      for (std::size_t k = i; k < i + length; ++k) {
        char escaped[8];
        std::snprintf(escaped, sizeof escaped, "\\x%02X", static_cast<unsigned char>(text[k]));
        shown += escaped;
      }
    } else {
      shown.append(text.substr(i, length));
    }
    i += length;
  }
  if (i < text.size()) shown += "...";
  return shown;
}

/// One data record into a row, or the reason it is bad.
Result<ImportRow> ParseRow(const Mapping& mapping, const CsvRecord& record) {
  if (record.fields.size() != mapping.width) {
    return Error{ErrorCode::kInvalid, "expected " + std::to_string(mapping.width) +
                                          " fields, got " + std::to_string(record.fields.size())};
  }
  // Trimmed of Unicode spaces, not only ASCII ones: a field that passed through a spreadsheet may
  // end in U+00A0, and a name stored with one would not match its seeded self.
  const auto field = [&](Column c) -> std::string {
    return mapping.index[c] < 0 ? std::string()
                                : std::string(TrimUnicodeSpaces(record.fields[mapping.index[c]]));
  };
  const auto optional = [&](Column c) -> std::optional<std::string> {
    if (mapping.index[c] < 0) return std::nullopt;
    std::string value = field(c);
    if (MeansUnknown(value)) return std::nullopt;
    return value;
  };
  const ParsedPincode pincode = ParsePincode(field(kPincode));
  if (!pincode) return Error{ErrorCode::kInvalid, "pincode: " + pincode.error};
  ImportRow row{record.line, *pincode.pincode, {}};
  PostOffice& office = row.office;
  office.branch_type = NormalizedOfficeType(optional(kType));
  office.name = StripTypeSuffix(field(kOffice), office.branch_type);
  office.delivery = optional(kDelivery);
  office.division = field(kDivision);
  office.region = field(kRegion);
  office.circle = field(kCircle);
  office.district = field(kDistrict);
  office.state = field(kState);
  office.taluk = optional(kTaluk);
  for (const auto& [column, target, name] :
       {std::tuple{kLatitude, &office.latitude, "latitude"},
        std::tuple{kLongitude, &office.longitude, "longitude"}}) {
    if (const auto text = optional(column)) {
      *target = ParseNumber(*text);
      if (!*target) {
        return Error{ErrorCode::kInvalid,
                     std::string(name) + " '" + ShownField(*text) + "' is not a number"};
      }
    }
  }
  if (auto error = detail::CheckOffice(office)) return *error;
  return row;
}

/// Counts a bad row, and keeps its message while fewer than kMaxProblemsKept are kept.
void AddProblem(ImportReport& report, RowProblem problem) {
  ++report.bad_rows;
  if (report.problems.size() < kMaxProblemsKept) report.problems.push_back(std::move(problem));
}

}  // namespace

const char* ToString(CsvLayout layout) {
  return layout == CsvLayout::kNewer ? "newer (with latitude/longitude)" : "older (with taluk)";
}

Result<ParsedImport> ParseDirectoryCsv(std::string_view csv, const ImportOptions& options) {
  const auto progress = [&](std::string_view phase, std::uint64_t done, std::uint64_t total) {
    if (options.progress) options.progress(phase, done, total);
  };
  if (const std::optional<std::string> not_csv = NotCsvText(csv)) {
    return Error{ErrorCode::kInvalid, *not_csv};
  }
  CsvReader reader(csv);
  std::string error;
  const auto header = reader.next(&error);
  if (!header) return Error{ErrorCode::kInvalid, "the file is empty"};
  if (!error.empty()) {
    return Error{ErrorCode::kInvalid,
                 "line 1: not an All India Pincode Directory header (" + error + ")"};
  }
  const Result<Mapping> mapping = Detect(header->fields);
  if (!mapping) return mapping.error();

  // Parse and check everything before touching the database.
  ParsedImport parsed;
  ImportReport& report = parsed.report;
  report.layout = mapping->layout;
  std::vector<ImportRow>& rows = parsed.rows;
  // An office twice in one file: the first is kept. A row that repeats it (or adds only details
  // it lacked, which are then taken) is counted; one that contradicts it is a bad row (applying
  // both would leave the last one, and each re-import would change the office twice).
  std::map<std::pair<std::uint32_t, std::string>, std::size_t> first_of;
  while (const auto record = reader.next(&error)) {
    ++report.rows;
    if (error == kUnterminatedQuote) {
      // The reader ran to the end of the file inside the quote: every line after it is lost
      // in one field, and which of them were rows cannot be told.
      return Error{ErrorCode::kInvalid,
                   "line " + std::to_string(record->quote_line) +
                       ": a quoted field opens here and is never closed, so the rest of the "
                       "file cannot be read as rows; nothing was imported"};
    }
    if (record->last_line > record->line) {
      // No directory field holds a line break. One quote too many (a remark "see note) joins
      // every line up to the next quote into one field, in a column the importer may not read,
      // so the record would otherwise pass with those lines' offices gone unnoticed.
      AddProblem(report, {record->line,
                          "lines " + std::to_string(record->line) + "-" +
                              std::to_string(record->last_line) +
                              " were read as one row: a quoted field opening on line " +
                              std::to_string(record->line_break_quote_line) +
                              " holds line breaks, which no directory field has (an unbalanced "
                              "quote?); none of these lines was imported"});
      continue;
    }
    if (!error.empty()) {
      AddProblem(report, {record->line, error});
      continue;
    }
    Result<ImportRow> row = ParseRow(*mapping, *record);
    if (!row) {
      AddProblem(report, {record->line, row.error().message});
      continue;
    }
    const auto [first, inserted] =
        first_of.try_emplace({row->pincode.value(), row->office.name}, rows.size());
    if (!inserted) {
      ImportRow& kept = rows[first->second];
      if (MergeRepeat(kept.office, row->office)) {
        ++report.repeated_rows;
      } else {
        AddProblem(report,
                   {record->line, "office '" + row->office.name + "' of " + row->pincode.str() +
                                      " is on line " + std::to_string(kept.line) +
                                      " too, with other details; that one is kept"});
      }
      continue;
    }
    rows.push_back(std::move(row).value());
    if (report.rows % kProgressEvery == 0) progress("parse", reader.position(), csv.size());
  }
  if (report.rows == 0) {
    return Error{ErrorCode::kInvalid, "the file has a header and no data rows; nothing to import"};
  }
  progress("parse", csv.size(), csv.size());
  return parsed;
}

Result<ImportReport> ApplyDirectoryCsv(Connection& connection, ParsedImport parsed,
                                       const ImportOptions& options) {
  const auto progress = [&](std::string_view phase, std::uint64_t done, std::uint64_t total) {
    if (options.progress) options.progress(phase, done, total);
  };
  ImportReport& report = parsed.report;
  const std::vector<ImportRow>& rows = parsed.rows;
  report.applied = false;
  if (options.strict && report.bad_rows > 0) return report;  // applied stays false

  const std::string source = options.source.empty() ? std::string(report.layout == CsvLayout::kNewer
                                                                      ? "import:india-post-newer"
                                                                      : "import:india-post-older")
                                                    : options.source;
  return detail::Guard([&]() -> Result<ImportReport> {
    Transaction transaction(connection);
    KeyAllocator allocator = detail::LoadKeyAllocator(connection);
    std::unordered_set<std::uint32_t> known;
    {
      Statement all = connection.prepare("SELECT pincode FROM pincodes");
      while (all.step()) known.insert(static_cast<std::uint32_t>(all.getInt64(0)));
    }
    Statement upsert = connection.prepare(detail::UpsertOfficeSql());
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const ImportRow& row = rows[i];
      if (known.insert(row.pincode.value()).second) {
        const auto key = detail::InsertPincode(connection, allocator, row.pincode, source);
        if (!key) {
          return Error{ErrorCode::kFull, "line " + std::to_string(row.line) + ": no key left for " +
                                             row.pincode.str() + "; nothing was imported"};
        }
        report.pincodes_added.emplace_back(row.pincode, *key);
      }
      const bool renamed = RenameSuffixedTwin(connection, row.pincode, row.office);
      const detail::OfficeMatch match =
          detail::ClaimOffice(connection, row.pincode, row.office.name);
      detail::BindOffice(upsert, row.pincode, row.office, source);
      const int changed = upsert.run();
      upsert.reset();
      if (match == detail::OfficeMatch::kNone) {
        ++report.offices_added;
      } else if (changed > 0 || renamed || match == detail::OfficeMatch::kClaimed) {
        ++report.offices_updated;
      } else {
        ++report.offices_unchanged;
      }
      if (i % kProgressEvery == 0) progress("write", i, rows.size());
    }
    progress("write", rows.size(), rows.size());
    transaction.commit();
    report.applied = true;
    return report;
  });
}

Result<ImportReport> ImportDirectoryCsv(Connection& connection, std::string_view csv,
                                        const ImportOptions& options) {
  Result<ParsedImport> parsed = ParseDirectoryCsv(csv, options);
  if (!parsed) return parsed.error();
  return ApplyDirectoryCsv(connection, std::move(parsed).value(), options);
}

Result<std::string> ReadImportFile(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    return Error{ErrorCode::kInvalid, path + " is a directory; give the CSV file itself"};
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{ErrorCode::kNotFound, "cannot read " + path + ": " + std::strerror(errno)};
  return ReadImportStream(in, path);
}

Result<std::string> ReadImportStream(std::istream& in, const std::string& name) {
  std::string text;
  std::array<char, 1 << 16> chunk{};
  while (in.read(chunk.data(), chunk.size()) || in.gcount() > 0) {
    if (text.size() + static_cast<std::size_t>(in.gcount()) > kMaxImportFileBytes) {
      return Error{ErrorCode::kTooLarge,
                   name + " is larger than " + std::to_string(kMaxImportFileBytes >> 20) +
                       " MiB, more than any pincode directory (India Post's whole directory is "
                       "about 20 MB)"};
    }
    text.append(chunk.data(), static_cast<std::size_t>(in.gcount()));
  }
  if (in.bad()) {
    return Error{ErrorCode::kStorage, "error reading " + name + ": " + std::strerror(errno)};
  }
  return text;
}

Result<ImportReport> ImportDirectoryCsvFile(Connection& connection, const std::string& path,
                                            const ImportOptions& options) {
  Result<std::string> text = ReadImportFile(path);
  if (!text) return text.error();
  return ImportDirectoryCsv(connection, *text, options);
}

}  // namespace pintag::db
