#pragma once
// The one config loader: YAML <-> any struct that lists its parameters through
// ParamVisitor (core/params.hpp). Unknown keys and bad values are errors naming the key.
#include <filesystem>
#include <functional>
#include <string>

#include "semap/core/params.hpp"

namespace YAML {
class Node;
}

namespace semap {

/// Applies the YAML file's values over the defaults held by `tree`. Throws semap::Error
/// naming the file and the key for unknown keys, wrong types or malformed YAML, and when the
/// path is not a regular file (a folder, a FIFO: core/paths read_regular_file).
void load_config_file(const std::filesystem::path& yaml_path, const ParamTree& tree);
/// Same, from a YAML string (`source` names it in messages).
void load_config_string(const std::string& yaml, const std::string& source, const ParamTree& tree);
/// The one strict YAML parse of the project (configs, dataset.yaml): a UTF-8 BOM is skipped;
/// more than one document ('---'), a key repeated in a map, or nesting deeper than 64 levels is
/// a semap::Error naming `source` and the line. Empty text gives a null node.
YAML::Node parse_yaml_strict(const std::string& text, const std::string& source);

/// YAML text of every parameter with its current value, unit and doc as comments.
std::string dump_config(const ParamTree& tree);

}  // namespace semap
