// semap: RGB-D sequence -> trajectory, semantic TSDF mesh and object map.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>

#include "apps/semap/commands.hpp"
#include "semap/core/error.hpp"

int main(int argc, char** argv) {
  CLI::App app{"semap: semantic mapping from RGB-D sequences (trajectory, semantic TSDF mesh, object map)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "semap 0.1.0");
  bool verbose = false;
  app.add_flag("-v,--verbose", verbose, "debug logging");

  semap::app::CommandRunner run;
  semap::app::add_synth_command(app, run);
  semap::app::add_run_command(app, run);
  semap::app::add_demo_command(app, run);
  semap::app::add_eval_command(app, run);
  semap::app::add_segment_command(app, run);
  semap::app::add_view_command(app, run);
  semap::app::add_config_command(app, run);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  spdlog::set_level(verbose ? spdlog::level::debug : spdlog::level::info);
  spdlog::set_pattern("[%^%l%$] %v");
  try {
    return run ? run() : 0;
  } catch (const semap::Error& e) {
    std::fprintf(stderr, "semap: error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "semap: error: %s\n", e.what());
    return 1;
  }
}
