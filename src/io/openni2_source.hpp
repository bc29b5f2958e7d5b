#pragma once
// Internal to io/: OpenNI2 cameras and .oni recordings through PCL's OpenNI2 grabber
// (openni2_source.cpp, the only file of io/ that includes PCL).
#include <memory>
#include <string>

#include "semap/io/frame_source.hpp"

namespace semap::io_detail {

/// True when built with PCL's io module and OpenNI2 (SEMAP_WITH_OPENNI2).
bool openni2_available();
/// `spec` is the whole "openni2:..." text (named in errors), `target` what follows the prefix:
/// "" (first device), a device URI, or an .oni file.
std::unique_ptr<FrameSource> open_openni2(const std::string& spec, const std::string& target);

}  // namespace semap::io_detail
