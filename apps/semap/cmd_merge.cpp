// `semap merge A B --out C`: two saved maps of the same place, made independently, as one
// (issue 19; semap/pipeline/map_merge.hpp).
#include <cstdio>

#include "apps/semap/commands.hpp"
#include "io/output_folder.hpp"
#include "pipeline/report.hpp"
#include "semap/pipeline/map_merge.hpp"

namespace semap::app {

void add_merge_command(CLI::App& app, CommandRunner& run) {
  auto* cmd = app.add_subcommand(
      "merge", "Merge two saved maps of the same place (output folders of `semap run` or `semap merge`) into the first's world frame");
  struct Args {
    std::string a, b, out;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("map_a", args->a, "the map whose world frame the result keeps (a folder or its map.semap)")->required();
  cmd->add_option("map_b", args->b, "the map relocalised into it")->required();
  cmd->add_option("--out", args->out, "output folder (published only when the merge succeeded)")->required();
  cmd->callback([&run, args] {
    run = [args]() -> int {
      const InterruptGuard interrupts;
      const MapMergeResult result = merge_maps(args->a, args->b, args->out);
      if (!result.merged) throw Error(args->b, result.reason + "; nothing written");
      std::fputs(summary_table(to_json(result)).c_str(), stdout);
      std::printf("merged map in %s\n", args->out.c_str());
      return 0;
    };
  });
}

}  // namespace semap::app
