#pragma once
// The one exception type thrown at boundaries (io, config, model loading). main() turns it
// into a one-line message "semap: FILE: REASON" and exit code 1.
#include <filesystem>
#include <stdexcept>
#include <string>

namespace semap {

class Error : public std::runtime_error {
 public:
  /// An error about a file (or folder, or config key): "WHERE: WHAT".
  Error(const std::string& where, const std::string& what)
      : std::runtime_error(where.empty() ? what : where + ": " + what), where_(where), what_(what) {}
  Error(const std::filesystem::path& where, const std::string& what) : Error(where.string(), what) {}
  Error(const char* where, const std::string& what) : Error(std::string(where), what) {}
  explicit Error(const std::string& what) : Error(std::string{}, what) {}

  const std::string& where() const { return where_; }
  const std::string& reason() const { return what_; }

 private:
  std::string where_;
  std::string what_;
};

}  // namespace semap
