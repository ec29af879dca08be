// The `pintag` command: one executable, one subcommand per job.

#include <exception>
#include <iostream>

#include "commands/commands.hpp"

int main(int argc, char** argv) {  // NOLINT(bugprone-exception-escape): CLI11's exit() only prints
  CLI::App app{"PinTag: colour fiducial markers that carry Indian pincodes", "pintag"};
  app.require_subcommand(1);
  pintag::cli::AddRegisteredCommands(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // CLI11 prints the message (or the help); its own codes (100 and up) mean a usage error too.
    return app.exit(e) == 0 ? 0 : 2;
  } catch (const pintag::cli::UsageError& e) {
    std::cerr << "pintag: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "pintag: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
