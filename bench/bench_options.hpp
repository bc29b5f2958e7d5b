// Command-line options of the benchmark programs: "--key value" pairs, --help, and one clear
// line (exit code 2) for an unknown key, a key without its value, or a value that does not parse.
#pragma once

#include <functional>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace semap::bench {

/// Calls handle(key, value) for each "--key value" pair of argv[first..]; handle returns false
/// for a key it does not know. Returns nothing to go on, or the exit code to leave with: 0 after
/// --help (usage printed), 2 after an error.
inline std::optional<int> parse_options(int argc, char** argv, int first, std::string_view usage,
                                        const std::function<bool(const std::string&, const std::string&)>& handle) {
  const std::string program = argc > 0 ? std::string(argv[0]).substr(std::string(argv[0]).find_last_of('/') + 1) : "bench";
  for (int i = first; i < argc; i += 2) {
    const std::string key = argv[i];
    if (key == "--help" || key == "-h") {
      std::cout << "usage: " << program << " " << usage << "\n";
      return 0;
    }
    if (i + 1 >= argc) {
      std::cerr << program << ": option " << key << " needs a value (--help lists the options)\n";
      return 2;
    }
    try {
      if (handle(key, argv[i + 1])) continue;
      std::cerr << program << ": unknown option " << key << " (--help lists the options)\n";
    } catch (const std::exception&) {  // std::stoi and friends
      std::cerr << program << ": option " << key << ": cannot read value '" << argv[i + 1] << "'\n";
    }
    return 2;
  }
  return std::nullopt;
}

}  // namespace semap::bench
