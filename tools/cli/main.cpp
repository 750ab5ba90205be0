// mltfarm command line: one subcommand per tools/cli/cmd_*.cpp (see commands.h).
#include <algorithm>
#include <cstdio>
#include <exception>
#include <map>

#include "tools/cli/commands.h"

int main(int argc, char** argv) {
  using namespace mlt::cli;
  CLI::App app{"mltfarm: a Metropolis light transport render farm"};
  app.require_subcommand(1);
  auto& registry = commandRegistry();
  std::sort(registry.begin(), registry.end(), [](const CommandInfo& a, const CommandInfo& b) { return a.name < b.name; });
  std::map<CLI::App*, CommandRun> runs;
  try {
    for (const CommandInfo& c : registry) {
      CLI::App* sub = app.add_subcommand(c.name, c.description);
      runs[sub] = c.setup(*sub);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mltfarm: internal error while setting up the command line: %s\n", e.what());
    return kExitError;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  for (auto& [sub, run] : runs) {
    if (!sub->parsed()) continue;
    try {
      return run();
    } catch (const std::exception& e) {
      std::fprintf(stderr, "mltfarm %s: error: %s\n", sub->get_name().c_str(), e.what());
      return kExitError;
    }
  }
  return 0;
}
