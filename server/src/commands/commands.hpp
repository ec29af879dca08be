#pragma once
// Subcommands of `pintag`. Each lives in its own file in this folder and registers itself with a
// file-scope `const CommandRegistration name_registration{"name", &AddNameCommand};`; main adds
// them to the app in name order. The files are compiled as one unit (server/CMakeLists.txt), so
// names in their anonymous namespaces must differ from file to file.

#include <CLI/CLI.hpp>
#include <stdexcept>
#include <string_view>

namespace pintag::cli {

/// Thrown by a command's action for a user error; main prints "pintag: <message>" and exits 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

using AddCommand = void (*)(CLI::App& app);

struct CommandRegistration {
  CommandRegistration(std::string_view name, AddCommand add);
};

/// Adds every registered subcommand to `app`, sorted by name.
void AddRegisteredCommands(CLI::App& app);

}  // namespace pintag::cli
