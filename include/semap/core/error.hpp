#pragma once
// The one exception type thrown at boundaries (io, config, model loading). main() turns it
// into a one-line message "semap: FILE: REASON" and exit code 1.
//
// A message stays one readable line whatever the input: control characters (a newline in a
// file name) are shown as \xNN, and a huge file name or quoted field is shortened to its head
// and tail with the full length (message_text); numbers are printed compactly
// (compact_number: 1.79769e+308, never 309 digits).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

namespace semap {

/// `text` made fit for a one-line message: control bytes and invisible Unicode format
/// characters (BOM, zero-width space, no-break space) as \xNN / \u{XXXX}, and at most
/// `max_chars` characters (head ... tail, with the original length).
inline std::string message_text(std::string_view text, size_t max_chars = 300) {
  std::string out;
  const auto append_escaped = [&out](std::string_view part) {
    for (size_t i = 0; i < part.size(); ++i) {
      const auto c = static_cast<unsigned char>(part[i]);
      const auto next = [&](size_t k) { return i + k < part.size() ? static_cast<unsigned char>(part[i + k]) : 0; };
      char buffer[16];
      if (c < 0x20 || c == 0x7f) {
        std::snprintf(buffer, sizeof buffer, "\\x%02X", c);
        out += buffer;
      } else if (c == 0xEF && next(1) == 0xBB && next(2) == 0xBF) {
        out += "\\u{FEFF}";  // byte-order mark
        i += 2;
      } else if (c == 0xE2 && next(1) == 0x80 && next(2) >= 0x8B && next(2) <= 0x8F) {
        std::snprintf(buffer, sizeof buffer, "\\u{20%02X}", 0x0B + (next(2) - 0x8B));  // zero-width, LRM, RLM
        out += buffer;
        i += 2;
      } else if (c == 0xC2 && next(1) == 0xA0) {
        out += "\\u{00A0}";  // no-break space
        i += 1;
      } else {
        out += static_cast<char>(c);
      }
    }
  };
  if (text.size() <= max_chars) {
    append_escaped(text);
    return out;
  }
  const size_t head = max_chars * 2 / 3, tail = max_chars / 4;
  append_escaped(text.substr(0, head));
  out += "...(" + std::to_string(text.size()) + " characters)...";
  append_escaped(text.substr(text.size() - tail));
  return out;
}

/// Shortest of %g-style forms with 6 significant digits: 0.02, 5000, 1e+12, 1.79769e+308, nan.
inline std::string compact_number(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.6g", value);
  return buffer;
}

class Error : public std::runtime_error {
 public:
  /// An error about a file (or folder, or config key): "WHERE: WHAT".
  Error(const std::string& where, const std::string& what)
      : std::runtime_error(compose(where, what)), where_(where), what_(what) {}
  Error(const std::filesystem::path& where, const std::string& what) : Error(where.string(), what) {}
  Error(const char* where, const std::string& what) : Error(std::string(where), what) {}
  explicit Error(const std::string& what) : Error(std::string{}, what) {}

  const std::string& where() const { return where_; }
  const std::string& reason() const { return what_; }

 private:
  static std::string compose(const std::string& where, const std::string& what) {
    const std::string reason = message_text(what, 2000);
    return where.empty() ? reason : message_text(where, 400) + ": " + reason;
  }
  std::string where_;
  std::string what_;
};

/// Thrown when SIGINT/SIGTERM asked the program to stop (io/output_folder.hpp); main() exits
/// with 128 + the signal number and nothing is published.
class Interrupted : public Error {
 public:
  explicit Interrupted(int signal_number)
      : Error("semap", std::string("interrupted by ") + (signal_number == 15 ? "SIGTERM" : "SIGINT") +
                           "; nothing of this run was published"),
        signal_(signal_number) {}
  int signal_number() const { return signal_; }

 private:
  int signal_;
};

}  // namespace semap
