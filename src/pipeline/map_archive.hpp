#pragma once
// The sections of a Mapper's map.semap (issue 19) that belong to no single stage: the camera and
// the configuration. The stages encode their own (tsdf/map_io, tracking/tracker_state,
// objects/object_map_io, objects/best_views); core/archive holds the container.
#include <filesystem>
#include <string>
#include <string_view>

#include "semap/core/camera.hpp"
#include "semap/pipeline/semap_config.hpp"

namespace semap {

inline constexpr const char* kCameraSection = "camera";
inline constexpr const char* kConfigSection = "config";

std::string encode_camera_section(const CameraModel& camera);
CameraModel decode_camera_section(std::string_view bytes, const std::filesystem::path& path);

/// The configuration as YAML (semap config --dump format, current values).
std::string encode_config_section(const SemapConfig& config);
SemapConfig decode_config_section(const std::string& yaml, const std::filesystem::path& path);

/// A saved map given as an output folder (its map.semap) or as the file itself (--resume,
/// semap merge).
std::filesystem::path map_file_of(const std::filesystem::path& folder_or_file);

/// Throws Error(path, ...) naming the first tracking.fern_* key whose value differs: the saved
/// keyframes' fern codes compare only with codes of the same ferns (METHODS A3).
void require_same_ferns(const TrackingConfig& saved, const TrackingConfig& given, const std::filesystem::path& path);

}  // namespace semap
