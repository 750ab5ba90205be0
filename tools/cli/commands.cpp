// The registry of subcommands (commands.h). Not in main.cpp, so that tests linking the subcommands
// without main can list and set them up.
#include "tools/cli/commands.h"

namespace mlt::cli {

std::vector<CommandInfo>& commandRegistry() {
  static std::vector<CommandInfo> registry;  // a function-local static: registrations run at static init
  return registry;
}

}  // namespace mlt::cli
