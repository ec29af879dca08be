// `pintag scans prune`: removes old scans from a scan log, a primary's (in its --db) or a
// replica's own file (--scan-log), in batches while its server goes on writing. A scan log grows
// by every photo read, and nothing else takes rows out of it.

#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "commands/commands.hpp"
#include "commands/open_db.hpp"
#include "commands/option_checks.hpp"
#include "pintag/db/scan_log.hpp"

namespace pintag::cli {
namespace {

struct ScansArgs {
  std::string db;
  std::string scan_log;
  std::string before;
  std::optional<int> older_than_days;
};

db::Connection OpenScanLogToPrune(const ScansArgs& args) {
  if (!args.db.empty()) return OpenExistingDb(args.db);
  std::error_code error;
  // OpenScanLogFile makes a missing file: a mistyped path is said instead.
  if (!std::filesystem::is_regular_file(args.scan_log, error)) {
    throw std::runtime_error("scan log " + args.scan_log + " does not exist");
  }
  db::Result<db::Connection> opened = db::OpenScanLogFile(args.scan_log);
  if (!opened) throw std::runtime_error(opened.error().message);
  return std::move(opened.value());
}

void Prune(const ScansArgs& args) {
  if (args.db.empty() == args.scan_log.empty()) {
    throw UsageError("give --db FILE (a registry's scan log) or --scan-log FILE (a replica's own)");
  }
  if (!args.before.empty() == args.older_than_days.has_value()) {
    throw UsageError("give --before DATE or --older-than-days N");
  }
  const std::string before = args.older_than_days
                                 ? db::ScanTime(std::chrono::system_clock::now() -
                                                std::chrono::days(*args.older_than_days))
                                 : args.before;
  const std::string& path = args.db.empty() ? args.scan_log : args.db;
  db::Connection connection = OpenScanLogToPrune(args);
  const db::Result<std::uint64_t> removed = db::PruneScans(connection, before);
  if (!removed) {
    if (removed.error().code == db::ErrorCode::kInvalid) throw UsageError(removed.error().message);
    // Each batch is committed on its own: those before the failure stay removed.
    throw std::runtime_error(removed.error().message +
                             " (scans removed before it stay removed; "
                             "run it again to go on)");
  }
  std::cout << "removed " << *removed << (*removed == 1 ? " scan" : " scans") << " taken before "
            << before << " from " << path
            << " (the file keeps its size: later scans reuse the room)\n";
}

void AddScansCommand(CLI::App& app) {
  auto args = std::make_shared<ScansArgs>();
  CLI::App* scans = app.add_subcommand("scans", "The scan log: one row per photo read");
  scans->require_subcommand(1);
  CLI::App* prune = scans->add_subcommand(
      "prune", "Remove the scans taken before a date, in batches, while a server writes on");
  prune->add_option("--db", args->db, "registry database whose scan log to prune (a primary's)")
      ->check(DatabaseFileName());
  prune->add_option("--scan-log", args->scan_log, "a replica's own scan log file (-scans.db)");
  prune->add_option("--before", args->before,
                    "remove scans taken before this UTC date (YYYY-MM-DD) or time "
                    "(YYYY-MM-DDTHH:MM:SS.mmmZ)");
  prune
      ->add_option("--older-than-days", args->older_than_days,
                   "remove scans taken more than N days ago (0-36500)")
      ->check(CLI::Range(0, 36500));
  prune->callback([args] { Prune(*args); });
}

const CommandRegistration scans_registration{"scans", &AddScansCommand};

}  // namespace
}  // namespace pintag::cli
