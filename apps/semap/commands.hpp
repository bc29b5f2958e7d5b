#pragma once
// One file per subcommand; each adds itself to the CLI11 app. The returned callback runs
// after parsing and returns the exit code.
#include <CLI/CLI.hpp>
#include <functional>

namespace semap::app {

using CommandRunner = std::function<int()>;

/// Each command registers its options on `app` and stores its runner in `run`.
void add_synth_command(CLI::App& app, CommandRunner& run);
void add_eval_command(CLI::App& app, CommandRunner& run);
void add_run_command(CLI::App& app, CommandRunner& run);
void add_demo_command(CLI::App& app, CommandRunner& run);
void add_segment_command(CLI::App& app, CommandRunner& run);
void add_view_command(CLI::App& app, CommandRunner& run);
void add_config_command(CLI::App& app, CommandRunner& run);

}  // namespace semap::app
