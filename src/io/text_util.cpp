#include "io/text_util.hpp"

#include <charconv>

#include "semap/core/error.hpp"
#include "core/paths.hpp"

namespace semap::io_detail {

std::string read_file_bytes(const std::filesystem::path& path, uint64_t max_bytes, std::string_view what) {
  return read_regular_file(path, max_bytes, what);
}

size_t utf8_bom_length(std::string_view text) { return text.substr(0, 3) == "\xEF\xBB\xBF" ? 3 : 0; }

std::string quoted_field(std::string_view field) { return "'" + message_text(field, 40) + "'"; }

std::vector<std::string_view> split_fields(std::string_view line) {
  std::vector<std::string_view> fields;
  size_t i = 0;
  auto is_sep = [](char c) { return c == ' ' || c == '\t' || c == ',' || c == '\r'; };
  while (i < line.size()) {
    while (i < line.size() && is_sep(line[i])) ++i;
    size_t j = i;
    while (j < line.size() && !is_sep(line[j])) ++j;
    if (j > i) fields.push_back(line.substr(i, j - i));
    i = j;
  }
  return fields;
}

std::optional<double> parse_double(std::string_view field) {
  if (!field.empty() && field.front() == '+') field.remove_prefix(1);
  double value = 0.0;
  const auto [ptr, ec] = std::from_chars(field.data(), field.data() + field.size(), value);
  if (ec != std::errc() || ptr != field.data() + field.size() || field.empty()) return std::nullopt;
  return value;
}

bool is_blank_or_comment(std::string_view line) {
  for (char c : line) {
    if (c == '#') return true;
    if (c != ' ' && c != '\t' && c != '\r') return false;
  }
  return true;
}

std::vector<double> read_numbers(const std::filesystem::path& path) {
  const std::string text = read_file_bytes(path, kMaxTextFileBytes, "number file");
  std::vector<double> numbers;
  for_each_line(text, [&](std::string_view line, size_t line_no) {
    if (is_blank_or_comment(line)) return;
    for (auto f : split_fields(line)) {
      const auto v = parse_double(f);
      if (!v) throw Error(where(path.string(), line_no), "malformed number " + quoted_field(f));
      numbers.push_back(*v);
    }
  });
  return numbers;
}

std::string where(const std::string& source, size_t line_no) {
  return source + ":" + std::to_string(line_no);
}

}  // namespace semap::io_detail
