#pragma once
// Small text helpers shared by the io parsers (TUM lists, trajectories, camera files).
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/paths.hpp"

namespace semap::io_detail {

/// Whole file as bytes (core/paths read_regular_file: regular files only, at most `max_bytes`);
/// throws semap::Error naming the file and saying what it is when it is not a readable file.
std::string read_file_bytes(const std::filesystem::path& path, uint64_t max_bytes = kMaxTextFileBytes,
                            std::string_view what = "file");
/// Length of a UTF-8 byte-order mark at the start of `text` (3 or 0). Editors on Windows add
/// one; every text parser skips it (for_each_line does).
size_t utf8_bom_length(std::string_view text);
/// A field of a file quoted in a message: invisible characters shown, at most 40 characters.
std::string quoted_field(std::string_view field);
/// Splits on spaces, tabs and commas (as TUM's associate.py does); drops '\r'.
std::vector<std::string_view> split_fields(std::string_view line);
/// Strict double parse of a whole field (no trailing characters); nullopt when malformed.
std::optional<double> parse_double(std::string_view field);
/// True for empty lines and '#' comments.
bool is_blank_or_comment(std::string_view line);
/// Calls fn(line, line_number) for each line (1-based numbering), after a UTF-8 BOM.
template <class F>
void for_each_line(std::string_view text, F&& fn) {
  size_t line_no = 0, start = utf8_bom_length(text);
  while (start < text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    fn(text.substr(start, end - start), ++line_no);
    start = end + 1;
  }
}
/// Every number in a text file (whitespace/comma separated, '#' comments skipped). Throws
/// naming FILE:LINE for a malformed token; NaN/Inf are returned (callers decide).
std::vector<double> read_numbers(const std::filesystem::path& path);
/// "FILE:LINE" for messages.
std::string where(const std::string& source, size_t line_no);

}  // namespace semap::io_detail
