#include "apps/semap/commands.hpp"
#include "core/error.hpp"

namespace semap::app {

void add_demo_command(CLI::App& app, CommandRunner& run) {
  auto* cmd = app.add_subcommand("demo", "Generate the synthetic world and map it end to end (not built yet)");
  cmd->allow_extras();
  cmd->callback([&run] {
    run = [] () -> int { throw Error("semap demo", "not built yet"); };
  });
}

}  // namespace semap::app
