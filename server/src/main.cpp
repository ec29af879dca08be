// The `pintag` command: one executable, one subcommand per job.

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <functional>
#include <iostream>
#include <string>
#include <string_view>

#include "commands/commands.hpp"
#include "commands/standard_output.hpp"
#include "pintag/db/database.hpp"
#include "pintag/server/log.hpp"

namespace {

/// 0, or 1 after saying so when what was printed on stdout could not all be written: a full disk
/// must not end in exit 0 with the output lost (`pintag token list > /dev/full`). A reader that
/// stopped reading (`pintag keys export | head -1`) is not an error to report: the status is the
/// one SIGPIPE would have given, and nothing is said.
int StdoutStatus() {
  std::cout.flush();
  if (!std::cout || std::fflush(stdout) != 0 || std::ferror(stdout) != 0) {
    if (pintag::cli::StandardOutputReaderHasGone()) return pintag::cli::kReaderGoneStatus;
    std::cerr << "pintag: cannot write to standard output\n";
    return 1;
  }
  return 0;
}

/// Why the command failed: on stderr, or for `serve --log-format json` as a JSON log line like
/// every other line it writes (a port taken, a database that cannot be opened).
void Report(const CLI::App& app, const char* what) {
  if (app.got_subcommand("serve") &&
      pintag::server::ConfiguredLogFormat() == pintag::server::LogFormat::kJson) {
    pintag::server::LogFatal(std::string("pintag: ") + what);
    return;
  }
  std::cerr << "pintag: " << what << "\n";
}

/// Whether `flag` is on the command line (`--db x` or `--db=x`).
bool OnCommandLine(std::string_view flag, int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg(argv[i]);
    if (arg == flag || (arg.starts_with(flag) && arg.substr(flag.size()).starts_with("="))) {
      return true;
    }
  }
  return false;
}

/// CLI11 names the option a bad value was given to ("--threads: Value 0 not in range 1 to 256",
/// "Could not convert: --read-only = banana"), and so do the commands' own checks ("--web /x is
/// not a directory"), also when the value came from the option's environment variable, which is
/// then named too: a container's PINTAG_THREADS is not on the command line the message points at.
std::string NamingTheEnvironment(const CLI::App& app, std::string message, int argc, char** argv) {
  const std::function<void(const CLI::App&)> visit = [&](const CLI::App& command) {
    for (const CLI::Option* option : command.get_options()) {
      const std::string& variable = option->get_envname();
      const char* value = variable.empty() ? nullptr : std::getenv(variable.c_str());
      if (value == nullptr) continue;
      const std::string flag = option->get_name();
      const bool names_it = message.rfind(flag + ":", 0) == 0 ||
                            message.rfind(flag + " ", 0) == 0 ||
                            message.find(": " + flag + " = ") != std::string::npos;
      // And about its value ("--follow needs a replica token" is no fault of PINTAG_FOLLOW's), or
      // about its being given at all: "--scan-log is for a replica …".
      const bool given_at_all = message.rfind(flag + " is ", 0) == 0;
      if (!names_it || (message.find(value) == std::string::npos && !given_at_all)) continue;
      // A value on the command line wins over the environment's.
      if (OnCommandLine(flag, argc, argv)) return;
      message += given_at_all ? " (set by the environment variable " + variable + ")"
                              : " (the value of the environment variable " + variable + ")";
      return;
    }
    for (const CLI::App* sub : command.get_subcommands()) visit(*sub);
  };
  visit(app);
  return message;
}

/// CLI11 takes an environment variable set to "" as not set, so `PINTAG_ADMIN_TOKEN_OUT=` (a shell
/// variable that was empty) printed the first admin secret to the log instead of writing a file.
/// Such a variable, for an option of `command` not on the command line, is a usage error: what it
/// says, or "".
std::string EmptyEnvironmentVariable(const CLI::App& command, int argc, char** argv) {
  for (const CLI::Option* option : command.get_options()) {
    const std::string& variable = option->get_envname();
    if (variable.empty()) continue;
    const char* value = std::getenv(variable.c_str());
    if (value == nullptr || *value != '\0') continue;
    const std::string flag = option->get_name();
    if (OnCommandLine(flag, argc, argv)) continue;  // the command line's value wins
    std::string problem = "the environment variable " + variable;
    problem += " (" + flag + ") is set but empty: give it a value or unset it";
    return problem;
  }
  // Into the subcommand named on the command line (`token create`), not its siblings.
  const std::function<bool(const CLI::App*)> every = [](const CLI::App*) { return true; };
  for (const CLI::App* sub : command.get_subcommands(every)) {
    const bool named =
        std::any_of(argv + 1, argv + argc, [&](const char* arg) { return sub->check_name(arg); });
    if (!named) continue;
    if (std::string problem = EmptyEnvironmentVariable(*sub, argc, argv); !problem.empty()) {
      return problem;
    }
  }
  return {};
}

}  // namespace

int main(int argc, char** argv) {  // NOLINT(bugprone-exception-escape): CLI11's exit() only prints
  // A reader that has gone (`pintag token create | head -c0`) is a write error to handle, not a
  // signal that ends the command: `token create` must live to revoke the token it could not show.
  // The server writes with MSG_NOSIGNAL already.
  std::signal(SIGPIPE, SIG_IGN);
  CLI::App app{"PinTag: colour fiducial markers that carry Indian pincodes", "pintag"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("pintag ") + PINTAG_VERSION + " (registry schema " +
                                        std::to_string(pintag::db::kSchemaVersion) + ")");
  pintag::cli::AddRegisteredCommands(app);
  // CLI11 answered a mistyped subcommand ("pintag serv") with "A subcommand is required".
  if (argc > 1 && argv[1][0] != '-') {
    const std::function<bool(CLI::App*)> every = [](CLI::App*) { return true; };
    std::string names;
    bool known = false;
    for (const CLI::App* sub : app.get_subcommands(every)) {
      names += (names.empty() ? "" : ", ") + sub->get_name();
      known = known || sub->check_name(argv[1]);
    }
    if (!known) {
      std::cerr << "pintag: '" << argv[1] << "' is not a subcommand; the subcommands are " << names
                << " (pintag --help)\n";
      return 2;
    }
  }
  if (argc > 1 && argv[1][0] != '-' && !OnCommandLine("--help", argc, argv) &&
      !OnCommandLine("-h", argc, argv)) {
    const CLI::App* command = app.get_subcommand(argv[1]);
    if (const std::string problem = EmptyEnvironmentVariable(*command, argc, argv);
        !problem.empty()) {
      std::cerr << "pintag: " << problem << "\n";
      return 2;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // CLI11 checks required options before unknown ones, so `render --kye 5` said "--key is
    // required" and hid the typo. An unknown option is then the message.
    if (dynamic_cast<const CLI::RequiredError*>(&e) != nullptr) {
      std::string unknown;
      for (const std::string& arg : app.remaining(true)) {
        if (arg.size() > 1 && arg.front() == '-') unknown += (unknown.empty() ? "" : ", ") + arg;
      }
      if (!unknown.empty()) {
        std::cerr << "pintag: unknown option " << unknown << " (" << e.what()
                  << ")\nRun with --help for more information.\n";
        return 2;
      }
    }
    if (e.get_exit_code() != 0) {
      const std::string message = NamingTheEnvironment(app, e.what(), argc, argv);
      if (message != e.what()) {
        std::cerr << message << "\nRun with --help for more information.\n";
        return 2;
      }
    }
    // CLI11 prints the message (or the help); its own codes (100 and up) mean a usage error too.
    return app.exit(e) == 0 ? StdoutStatus() : 2;
  } catch (const pintag::cli::UsageError& e) {
    Report(app, NamingTheEnvironment(app, e.what(), argc, argv).c_str());
    return 2;
  } catch (const std::exception& e) {
    Report(app, NamingTheEnvironment(app, e.what(), argc, argv).c_str());
    return 1;
  }
  // Not for serve, whose stdout is a banner and whose exit status says how it stopped.
  return app.got_subcommand("serve") ? 0 : StdoutStatus();
}
