#pragma once
// The browser viewer's static files (index.html, viewer.js), bundled with esbuild at build time
// and compiled into the semap executable (viewer/CMakeLists.txt), so `semap view` needs no
// install step and no files beside the binary.
#include <cstddef>
#include <span>
#include <string_view>

namespace semap::viewer {

struct Asset {
  std::string_view name;   ///< file name, e.g. "index.html"
  std::string_view bytes;  ///< file contents
};

/// The embedded files; empty when the viewer could not be built (no node/npm at build time).
std::span<const Asset> embedded_assets();
/// Why embedded_assets() is empty ("" when it is not).
std::string_view unavailable_reason();

}  // namespace semap::viewer
