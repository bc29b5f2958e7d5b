#include "semap/pipeline/semap_config.hpp"

#include "semap/io/config_loader.hpp"

namespace semap {

SemapConfig load_semap_config(const std::filesystem::path& yaml_path) {
  SemapConfig config;
  if (!yaml_path.empty()) load_config_file(yaml_path, [&](ParamVisitor& v) { config.visit(v); });
  config.validate();
  return config;
}

std::string dump_default_config() {
  SemapConfig config;
  return "# semap configuration: every parameter with its default.\n" +
         dump_config([&](ParamVisitor& v) { config.visit(v); });
}

}  // namespace semap
