#include "apps/semap/commands.hpp"
#include "core/error.hpp"

namespace semap::app {

void add_synth_command(CLI::App& app, CommandRunner& run) {
  auto* cmd = app.add_subcommand("synth", "Map a dataset: trajectory, semantic TSDF mesh, object map (not built yet)");
  cmd->allow_extras();
  cmd->callback([&run] {
    run = [] () -> int { throw Error("semap synth", "not built yet"); };
  });
}

}  // namespace semap::app
