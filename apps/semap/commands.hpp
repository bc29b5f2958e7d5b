#pragma once
// One file per subcommand; each adds itself to the CLI11 app. The returned callback runs
// after parsing and returns the exit code.
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <map>
#include <string>

#include "semap/core/error.hpp"
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
void add_merge_command(CLI::App& app, CommandRunner& run);
void add_query_command(CLI::App& app, CommandRunner& run);  // issue 39

/// An option whose value is one of an enum's names (a typo is a parse error listing them).
template <class E, size_t N>
CLI::Option* add_enum_option(CLI::App* cmd, const std::string& name, E& value, const EnumNames<E, N>& names,
                             const std::string& doc) {
  std::map<std::string, E> table;
  for (const auto& n : names) table.emplace(std::string(n.name), n.value);
  return cmd->add_option(name, value, doc + " (" + enum_choices(names) + ")")
      ->transform(CLI::CheckedTransformer(table, CLI::ignore_case));
}

/// A finite number in [lo, hi] (CLI11's Range and PositiveNumber let NaN through).
inline CLI::Validator finite_in(double lo, double hi) {
  const std::string range = "[" + compact_number(lo) + ", " + compact_number(hi) + "]";
  return CLI::Validator(
      [lo, hi, range](std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0' || !std::isfinite(v) || v < lo || v > hi)
          return "must be a finite number in " + range + ", got '" + message_text(text, 40) + "'";
        return {};
      },
      "FINITE in " + range);
}

}  // namespace semap::app
