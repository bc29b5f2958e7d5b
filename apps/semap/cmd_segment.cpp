#include "apps/semap/commands.hpp"
#include "core/error.hpp"

namespace semap::app {

void add_segment_command(CLI::App& app, CommandRunner& run) {
  auto* cmd = app.add_subcommand("segment", "Segment RGB images with an ONNX model (not built yet)");
  cmd->allow_extras();
  cmd->callback([&run] {
    run = [] () -> int { throw Error("semap segment", "not built yet"); };
  });
}

}  // namespace semap::app
