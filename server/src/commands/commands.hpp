#pragma once
// One function per `pintag` subcommand: each adds its subcommand, options and action to the app.

#include <CLI/CLI.hpp>

namespace pintag::cli {

/// Thrown by a command's action for a user error; main prints "pintag: <message>" and exits 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

void AddRenderCommand(CLI::App& app);

}  // namespace pintag::cli
