#pragma once
// The subcommands of the knitsim program. Each lives in its own cmd_*.cpp file and adds
// itself to the list below from there, so that a new command is one new file:
//
//   namespace knitsim {
//   void register_hello(CLI::App& app) { app.add_subcommand("hello", "…")->callback(…); }
//   const bool hello_added = add_command(95, register_hello);
//   }
//
// `order` places it in `knitsim --help` (the commands come in increasing order).
#include <CLI/CLI.hpp>

namespace knitsim {

using RegisterCommand = void (*)(CLI::App& app);

/// Adds a command to those register_commands registers; returns true (for a namespace-
/// scope constant, which runs it when the program starts).
bool add_command(int order, RegisterCommand register_command);

/// Registers every added command on `app`, in their order.
void register_commands(CLI::App& app);

}  // namespace knitsim
