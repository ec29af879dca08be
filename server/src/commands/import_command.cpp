// `pintag import FILE`: India Post "All India Pincode Directory" CSV into the registry.

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <iostream>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "commands/commands.hpp"
#include "commands/open_db.hpp"
#include "commands/option_checks.hpp"
#include "commands/standard_output.hpp"
#include "pintag/db/database.hpp"
#include "pintag/db/importer.hpp"

namespace pintag::cli {
namespace {

struct ImportArgs {
  std::string file;
  std::string db = "pintag.db";
  bool strict = false;
};

constexpr std::size_t kProblemsShown = 50;

/// A one-line bar on stderr, redrawn at most ten times a second.
class ProgressBar {
 public:
  void operator()(std::string_view phase, std::uint64_t done, std::uint64_t total) {
    const auto now = std::chrono::steady_clock::now();
    if (done < total && now - last_ < std::chrono::milliseconds(100)) return;
    last_ = now;
    constexpr int kWidth = 40;
    const double fraction = total == 0 ? 1.0 : static_cast<double>(done) / total;
    const int filled = static_cast<int>(fraction * kWidth);
    std::cerr << "\r" << phase << " [" << std::string(filled, '#')
              << std::string(kWidth - filled, ' ') << "] " << static_cast<int>(fraction * 100)
              << "%" << std::flush;
    drawn_ = true;
  }
  /// Erases the bar, so that what is said next starts a line of its own; the next call redraws it.
  void clear() {
    if (drawn_) std::cerr << "\r\033[K" << std::flush;
    drawn_ = false;
  }
  ~ProgressBar() { clear(); }

 private:
  std::chrono::steady_clock::time_point last_{};
  bool drawn_ = false;
};

/// "1 row", "4 rows": `count` and its noun, plural unless one.
std::string Counted(std::int64_t count, std::string_view noun) {
  std::string text = std::to_string(count) + " ";
  text += noun;
  if (count != 1) text += "s";
  return text;
}

/// The bad rows, as FILE:LINE: reason, the first kProblemsShown of them.
void PrintProblems(const std::string& file, const db::ImportReport& report) {
  const std::vector<db::RowProblem>& problems = report.problems;
  for (std::size_t i = 0; i < problems.size() && i < kProblemsShown; ++i) {
    std::cerr << file << ":" << problems[i].line << ": " << problems[i].message << "\n";
  }
  const std::int64_t shown = static_cast<std::int64_t>(std::min(problems.size(), kProblemsShown));
  if (report.bad_rows > shown) {
    std::cerr << "... and " << Counted(report.bad_rows - shown, "more bad row") << "\n";
  }
}

void Run(const ImportArgs& args) {
  // Read and checked before the database is opened: a missing file, one that is not a directory
  // CSV, one whose rows are all bad or (--strict) any bad, must not leave a new, seeded database.
  // `-` is standard input (`xzcat directory.csv.xz | pintag import -`), as for `pintag detect`.
  const bool from_stdin = args.file == "-";
  const std::string file = from_stdin ? "standard input" : args.file;
  const db::Result<std::string> csv =
      from_stdin ? db::ReadImportStream(std::cin, file) : db::ReadImportFile(file);
  if (!csv) throw std::runtime_error(csv.error().message);
  db::ImportOptions options;
  options.strict = args.strict;
  auto bar = std::make_shared<ProgressBar>();
  if (isatty(STDERR_FILENO)) {
    options.progress = [bar](std::string_view phase, std::uint64_t done, std::uint64_t total) {
      (*bar)(phase, done, total);
    };
  }
  db::Result<db::ParsedImport> parsed = db::ParseDirectoryCsv(*csv, options);
  if (!parsed) {
    bar.reset();
    throw std::runtime_error(file + ": " + parsed.error().message);
  }
  const std::int64_t bad_rows = parsed->report.bad_rows;
  if (bad_rows > 0 && (args.strict || parsed->rows.empty())) {
    bar.reset();
    PrintProblems(file, parsed->report);
    if (args.strict) {
      throw std::runtime_error("--strict: " + Counted(bad_rows, "bad row") + ", nothing imported");
    }
    throw std::runtime_error(file + (parsed->report.rows == 1
                                         ? std::string(": its one row could not be imported")
                                         : ": none of its " + Counted(parsed->report.rows, "row") +
                                               " could be imported"));
  }
  bar->clear();  // OpenDb may say it created the database
  db::Connection connection = OpenDb(args.db);
  auto result = db::ApplyDirectoryCsv(connection, std::move(parsed).value(), options);
  bar.reset();
  options.progress = nullptr;
  if (!result && result.error().code == db::ErrorCode::kBusy) {
    // SQLite's "database is locked" named the file being imported, as if it were at fault.
    throw std::runtime_error(LockedMessage(args.db, "nothing of " + file + " was imported"));
  }
  if (!result) {
    const std::string failure =
        DatabaseWriteFailure(args.db, result.error(), "nothing of " + file + " was imported");
    throw std::runtime_error(failure.empty() ? file + ": " + result.error().message : failure);
  }
  const db::ImportReport& report = *result;
  PrintProblems(file, report);
  std::cout << "imported " << file << " (" << db::ToString(report.layout)
            << " layout): " << Counted(report.rows, "row") << ", "
            << Counted(report.offices_added, "office") << " added, " << report.offices_updated
            << " updated, " << report.offices_unchanged << " unchanged, "
            << Counted(static_cast<std::int64_t>(report.pincodes_added.size()), "new pincode")
            << ", " << Counted(report.bad_rows, "bad row") << " skipped";
  if (report.repeated_rows > 0) std::cout << ", " << Counted(report.repeated_rows, "repeated row");
  std::cout << "\n";
  constexpr std::size_t kNewKeysShown = 20;
  for (std::size_t i = 0; i < report.pincodes_added.size() && i < kNewKeysShown; ++i) {
    const auto& [pincode, key] = report.pincodes_added[i];
    std::cout << "new pincode " << pincode.str() << " key " << key.value() << "\n";
  }
  if (report.pincodes_added.size() > kNewKeysShown) {
    std::cout << "... and " << report.pincodes_added.size() - kNewKeysShown
              << " more new pincodes (see `pintag keys export`)\n";
  }
  // The import is committed whatever became of its summary: a bare "cannot write to standard
  // output" and exit 1 read as if it had failed, and running it again would change nothing.
  std::cout << std::flush;
  if (!std::cout && !StandardOutputReaderHasGone()) {
    throw std::runtime_error("cannot write the summary to standard output; the import of " + file +
                             " into " + args.db +
                             " is committed (`pintag keys export` lists its keys)");
  }
}

void AddImportCommand(CLI::App& app) {
  auto args = std::make_shared<ImportArgs>();
  CLI::App* cmd = app.add_subcommand(
      "import", "Import India Post's All India Pincode Directory CSV (either layout)");
  cmd->add_option("file", args->file, "CSV file, or - for standard input")->required();
  cmd->add_option("--db", args->db, "database file (created and seeded when missing)")
      ->check(DatabaseFileName())
      ->capture_default_str();
  cmd->add_flag("--strict", args->strict, "refuse the whole file if any row is bad");
  cmd->callback([args] { Run(*args); });
}

const CommandRegistration import_registration{"import", &AddImportCommand};

}  // namespace
}  // namespace pintag::cli
