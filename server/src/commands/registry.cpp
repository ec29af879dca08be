#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "commands/commands.hpp"
#include "commands/option_checks.hpp"

namespace pintag::cli {
namespace {

// A function-local static, so registrations from other files' static initialisers find it built.
std::vector<std::pair<std::string, AddCommand>>& Registered() {
  static std::vector<std::pair<std::string, AddCommand>> commands;
  return commands;
}

/// Puts DecimalInteger first on every integer option of `app` and its subcommands.
void ReadIntegersAsDecimal(CLI::App& app) {
  for (CLI::Option* option : app.get_options()) {
    const std::string type = option->get_type_name();
    const std::string base = type.substr(0, type.find(':'));
    if (base != "INT" && base != "UINT") continue;
    try {
      option->get_validator(kReadsItsText);
    } catch (const CLI::OptionNotFound&) {
      option->transform(DecimalInteger());
    }
  }
  for (CLI::App* command : app.get_subcommands({})) ReadIntegersAsDecimal(*command);
}

}  // namespace

CommandRegistration::CommandRegistration(std::string_view name, AddCommand add) {
  Registered().emplace_back(std::string(name), add);
}

void AddRegisteredCommands(CLI::App& app) {
  auto commands = Registered();
  std::sort(commands.begin(), commands.end());
  for (const auto& [name, add] : commands) add(app);
  ReadIntegersAsDecimal(app);
}

}  // namespace pintag::cli
