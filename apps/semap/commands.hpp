#pragma once
// One file per subcommand; each adds itself to the CLI11 app. The returned callback runs
// after parsing and returns the exit code.
#include <CLI/CLI.hpp>
#include <cmath>
#include <functional>
#include <map>
#include <string>

#include "semap/core/params.hpp"

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

/// An option whose value is one of an enum's names (a typo is a parse error listing them).
template <class E, size_t N>
CLI::Option* add_enum_option(CLI::App* cmd, const std::string& name, E& value, const EnumNames<E, N>& names,
                             const std::string& doc) {
  std::map<std::string, E> table;
  for (const auto& n : names) table.emplace(std::string(n.name), n.value);
  return cmd->add_option(name, value, doc + " (" + enum_choices(names) + ")")
      ->transform(CLI::CheckedTransformer(table, CLI::ignore_case));
}

/// A finite number in [min, max] (CLI11's Range lets NaN through).
inline CLI::Validator finite_range(double min, double max) {
  return CLI::Validator(
      [min, max](std::string& text) -> std::string {
        double v = 0;
        if (!CLI::detail::lexical_cast(text, v) || !std::isfinite(v) || v < min || v > max)
          return "must be a number in [" + format_number(min) + ", " + format_number(max) + "], got '" + text + "'";
        return {};
      },
      "[" + format_number(min) + ", " + format_number(max) + "]");
}

}  // namespace semap::app
