// `pintag snapshot --db LIVE --out FILE`: a consistent copy of a live database for read-only
// replicas (`pintag serve --read-only`), renamed into place atomically; prints the registry
// version it holds. `pintag snapshot --verify FILE` checks a snapshot and prints its version.

#include <array>
#include <csignal>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "commands/commands.hpp"
#include "commands/option_checks.hpp"
#include "pintag/db/database.hpp"
#include "pintag/db/snapshot.hpp"

namespace pintag::cli {
namespace {

struct SnapshotArgs {
  std::string db = "pintag.db";
  std::string out;
  std::string verify;
};

/// Ends the process as `signal` would have, once the snapshot's temporary file is removed:
/// SA_RESETHAND has put the default action back, and the raised signal waits until this returns.
void RemoveTemporariesAndEnd(int signal) {
  db::RemoveSnapshotTemporariesOnSignal();
  ::raise(signal);
}

/// While alive, an interrupted or stopped snapshot leaves no temporary copy beside its output
/// (the copy of a large registry takes seconds). SIGKILL still can. A signal the process was
/// started ignoring stays ignored.
class TemporariesRemovedOnSignals {
 public:
  TemporariesRemovedOnSignals() {
    struct sigaction action {};
    action.sa_handler = RemoveTemporariesAndEnd;
    action.sa_flags = SA_RESETHAND;
    ::sigemptyset(&action.sa_mask);
    for (std::size_t i = 0; i < kSignals.size(); ++i) {
      ::sigaction(kSignals[i], nullptr, &previous_[i]);
      // Ignored (nohup, a background job of a script): it stays ignored, and the copy goes on.
      if (previous_[i].sa_handler != SIG_IGN) ::sigaction(kSignals[i], &action, nullptr);
    }
  }
  TemporariesRemovedOnSignals(const TemporariesRemovedOnSignals&) = delete;
  TemporariesRemovedOnSignals& operator=(const TemporariesRemovedOnSignals&) = delete;
  ~TemporariesRemovedOnSignals() {
    for (std::size_t i = 0; i < kSignals.size(); ++i) {
      ::sigaction(kSignals[i], &previous_[i], nullptr);
    }
  }

 private:
  static constexpr std::array<int, 4> kSignals = {SIGINT, SIGTERM, SIGHUP, SIGQUIT};
  std::array<struct sigaction, kSignals.size()> previous_{};
};

void Print(const db::SnapshotInfo& info) {
  std::cout << "snapshot " << info.path << ": registry version " << info.registry_version << ", "
            << info.bytes << " bytes\n";
}

void Run(const SnapshotArgs& args) {
  if (args.out.empty() && args.verify.empty()) throw UsageError("give --out FILE or --verify FILE");
  if (!args.out.empty() && !args.verify.empty()) {
    throw UsageError("give --out FILE or --verify FILE, not both");
  }
  // Before the snapshot is made: a device or a pipe would be replaced by the file.
  if (!args.out.empty()) CheckFileToReplace("--out", args.out);
  if (!args.verify.empty()) {
    auto info = db::VerifySnapshot(args.verify);
    if (!info) throw std::runtime_error(info.error().message);
    Print(*info);
    return;
  }
  // Never created here: a snapshot of a database that does not exist is a mistake.
  std::error_code ec;
  if (std::filesystem::is_regular_file(args.db, ec) &&
      std::filesystem::file_size(args.db, ec) == 0) {
    throw std::runtime_error(args.db + " is empty: not a PinTag database");
  }
  // Read only: a snapshot never changes its source (no migration, no seeding of an empty file).
  auto opened = db::OpenDatabase(args.db, {.create = false, .seed = false, .read_only = true});
  if (!opened) throw std::runtime_error(opened.error().message);
  const TemporariesRemovedOnSignals removed_on_signals;
  auto info = db::WriteSnapshot(opened.value().connection, args.out);
  if (!info) throw std::runtime_error(info.error().message);
  Print(*info);
}

void AddSnapshotCommand(CLI::App& app) {
  auto args = std::make_shared<SnapshotArgs>();
  CLI::App* cmd = app.add_subcommand(
      "snapshot", "Copy a live database into a snapshot for read-only replicas, atomically");
  cmd->add_option("--db", args->db, "the live database (must exist)")
      ->check(DatabaseFileName())
      ->capture_default_str();
  cmd->add_option("--out", args->out, "snapshot file to write (replaced atomically)")
      ->check(FileName());
  cmd->add_option("--verify", args->verify, "check this snapshot and print its registry version")
      ->check(FileName());
  cmd->callback([args] { Run(*args); });
}

const CommandRegistration registration{"snapshot", &AddSnapshotCommand};

}  // namespace
}  // namespace pintag::cli
