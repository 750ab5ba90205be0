// Subcommands of the `mltfarm` executable. Each tools/cli/cmd_*.cpp registers one subcommand with a
// file-scope CommandRegistration; main.cpp builds the CLI11 app from every registration, so adding a
// subcommand means adding one file and touching nothing else:
//
//   namespace mlt::cli {
//   static CommandRegistration reg("merge", "Merge partial EXRs offline", [](CLI::App& sub) {
//     auto opts = std::make_shared<MergeOptions>();
//     sub.add_option("parts", opts->parts)->required();
//     return [opts] { ... ; return 0; };  // runs after parsing; its value is the exit code
//   });
//   }
//
// Exit codes: 0 success; 2 an error while running (bad scene, unreadable file, ...): main prints the
// exception's message on stderr; CLI11's own codes for usage errors.
#pragma once
#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <vector>

namespace mlt::cli {

constexpr int kExitError = 2;

using CommandRun = std::function<int()>;
using CommandSetup = std::function<CommandRun(CLI::App& subcommand)>;

struct CommandInfo {
  std::string name, description;
  CommandSetup setup;
};

// All registrations, in no particular order (main sorts them by name).
std::vector<CommandInfo>& commandRegistry();

struct CommandRegistration {
  CommandRegistration(std::string name, std::string description, CommandSetup setup) {
    commandRegistry().push_back({std::move(name), std::move(description), std::move(setup)});
  }
};

}  // namespace mlt::cli
