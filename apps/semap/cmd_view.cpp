#include "apps/semap/commands.hpp"
#include "core/error.hpp"

namespace semap::app {

void add_view_command(CLI::App& app, CommandRunner& run) {
  auto* cmd = app.add_subcommand("view", "Serve an output folder in the browser viewer (not built yet)");
  cmd->allow_extras();
  cmd->callback([&run] {
    run = [] () -> int { throw Error("semap view", "not built yet"); };
  });
}

}  // namespace semap::app
