#pragma once
// Error text of nlohmann::json for a user (issue 44, class 8): its exceptions read
// "[json.exception.out_of_range.403] key 'id' not found"; the bracketed library tag says nothing
// to someone fixing a file, so messages keep only what follows it.
#include <exception>
#include <string>
#include <string_view>

namespace semap {

inline std::string json_error_text(const std::exception& e) {
  std::string_view text = e.what();
  if (text.starts_with("[json.exception.")) {
    const size_t end = text.find("] ");
    if (end != std::string_view::npos) text.remove_prefix(end + 2);
  }
  return std::string(text);
}

}  // namespace semap
