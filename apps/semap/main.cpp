// semap: RGB-D sequence -> trajectory, semantic TSDF mesh and object map.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <regex>
#include <string>

#include "apps/semap/commands.hpp"
#include "semap/core/error.hpp"

namespace {

/// CLI11 prints range bounds with std::to_string: DBL_MAX becomes 309 digits. Every decimal
/// number of 10 or more characters in its messages is rewritten compactly (1.79769e+308).
std::string compact_numbers(const std::string& message) {
  static const std::regex kLongNumber(R"([-+]?[0-9]+\.[0-9]{6}\b|[-+]?[0-9]{10,}(\.[0-9]+)?)");
  std::string out;
  auto last = message.cbegin();
  for (std::sregex_iterator it(message.begin(), message.end(), kLongNumber), end; it != end; ++it) {
    out.append(last, (*it)[0].first);
    out += semap::compact_number(std::strtod(it->str().c_str(), nullptr));
    last = (*it)[0].second;
  }
  out.append(last, message.cend());
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"semap: semantic mapping from RGB-D sequences (trajectory, semantic TSDF mesh, object map)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "semap 0.1.0");
  bool verbose = false;
  app.add_flag("-v,--verbose", verbose, "debug logging");

  semap::app::CommandRunner run;
  semap::app::add_synth_command(app, run);
  semap::app::add_run_command(app, run);
  semap::app::add_merge_command(app, run);
  semap::app::add_query_command(app, run);
  semap::app::add_demo_command(app, run);
  semap::app::add_eval_command(app, run);
  semap::app::add_segment_command(app, run);
  semap::app::add_view_command(app, run);
  semap::app::add_config_command(app, run);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help / --version are "errors" with exit code 0; every real parse error exits 1 (README).
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "semap: error: %s (see --help)\n",
                 compact_numbers(semap::message_text(e.what(), 2000)).c_str());
    return 1;
  }
  spdlog::set_level(verbose ? spdlog::level::debug : spdlog::level::info);
  spdlog::set_pattern("[%^%l%$] %v");
  try {
    return run ? run() : 0;
  } catch (const semap::Interrupted& e) {
    std::fprintf(stderr, "semap: %s\n", e.reason().c_str());
    return 128 + e.signal_number();
  } catch (const semap::Error& e) {
    std::fprintf(stderr, "semap: error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "semap: error: %s\n", semap::message_text(e.what(), 2000).c_str());
    return 1;
  }
}
