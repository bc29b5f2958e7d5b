#pragma once
// The one config loader: YAML <-> any struct that lists its parameters through
// ParamVisitor (core/params.hpp). Unknown keys and bad values are errors naming the key.
#include <filesystem>
#include <functional>
#include <string>

#include "semap/core/params.hpp"

namespace semap {

/// Applies the YAML file's values over the defaults held by `tree`. Throws semap::Error
/// naming the file and the key for unknown keys, wrong types or malformed YAML.
void load_config_file(const std::filesystem::path& yaml_path, const ParamTree& tree);
/// Same, from a YAML string (`source` names it in messages).
void load_config_string(const std::string& yaml, const std::string& source, const ParamTree& tree);
/// YAML text of every parameter with its current value, unit and doc as comments.
std::string dump_config(const ParamTree& tree);

}  // namespace semap
