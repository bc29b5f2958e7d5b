#include <cstdio>

#include "apps/semap/commands.hpp"
#include "semap/pipeline/semap_config.hpp"

namespace semap::app {

void add_config_command(CLI::App& app, CommandRunner& run) {
  auto* cmd = app.add_subcommand("config", "Print or check the YAML configuration");
  auto dump = std::make_shared<bool>(false);
  auto check = std::make_shared<std::string>();
  cmd->add_flag("--dump", *dump, "print every parameter with its default and doc");
  cmd->add_option("--check", *check, "validate a config file")->check(CLI::ExistingFile);
  cmd->callback([&run, dump, check] {
    run = [dump, check]() -> int {
      if (!check->empty()) {
        load_semap_config(*check);
        std::printf("%s: ok\n", check->c_str());
        return 0;
      }
      std::fputs(dump_default_config().c_str(), stdout);
      return 0;
    };
  });
}

}  // namespace semap::app
