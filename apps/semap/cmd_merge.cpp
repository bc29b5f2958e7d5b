// `semap merge A B --out C`: two saved maps of the same place, made independently, as one
// (issue 19; semap/pipeline/map_merge.hpp).
#include <cstdio>

#include "apps/semap/commands.hpp"
#include "core/paths.hpp"
#include "io/output_folder.hpp"
#include "pipeline/report.hpp"
#include "semap/pipeline/map_merge.hpp"

namespace semap::app {

namespace {

/// The output folder must not be one of the inputs: publishing there would replace its files.
void require_separate(const std::filesystem::path& input, const std::filesystem::path& out) {
  const std::filesystem::path folder = std::filesystem::is_directory(input) ? input : input.parent_path();
  std::error_code ec;
  if (std::filesystem::equivalent(folder, out, ec))
    throw Error(out, "is the folder of the input map " + input.string() + ": write the merged map elsewhere (inputs are only read)");
}

}  // namespace

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
      for (const std::string& input : {args->a, args->b})
        if (!std::filesystem::exists(input)) throw Error(input, "not found");
      if (std::filesystem::exists(args->out)) {
        require_separate(args->a, args->out);
        require_separate(args->b, args->out);
      }
      OutputFolder out(args->out, {.tool = "merge", .publish_last = {"report.json"}});
      const MapMergeResult result = merge_maps(args->a, args->b, out.staging());
      if (!result.merged) throw Error(args->b, result.reason + "; nothing written");
      const nlohmann::json report = to_json(result);
      write_file_atomic(out.staging() / "report.json", report.dump(2) + "\n");
      throw_if_interrupted();
      out.publish();
      std::fputs(summary_table(report).c_str(), stdout);
      std::printf("merged map in %s\n", args->out.c_str());
      return 0;
    };
  });
}

}  // namespace semap::app
