#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "commands/commands.hpp"

namespace pintag::cli {
namespace {

// A function-local static, so registrations from other files' static initialisers find it built.
std::vector<std::pair<std::string, AddCommand>>& Registered() {
  static std::vector<std::pair<std::string, AddCommand>> commands;
  return commands;
}

}  // namespace

CommandRegistration::CommandRegistration(std::string_view name, AddCommand add) {
  Registered().emplace_back(std::string(name), add);
}

void AddRegisteredCommands(CLI::App& app) {
  auto commands = Registered();
  std::sort(commands.begin(), commands.end());
  for (const auto& [name, add] : commands) add(app);
}

}  // namespace pintag::cli
