#pragma once
// Map save/load: versioned little-endian binary format with an FNV-1a 64 checksum.
//   "SEMAPMAP" | u32 version (1) | u32 header bytes | header | payload | u64 FNV-1a(header+payload)
//   header: f64 voxel_size, f64 truncation_voxels, f64 epsilon_voxels, f64 weight_unit,
//           f64 weight_max, f64 bayes_min_probability, u32 layers (1 label, 2 bayes, 4 colour),
//           u32 bayes_top_k, u64 block count
//   payload per block (sorted by z, y, x): i32 x y z | 512 x 4 B voxels | [512 B vote]
//           | [512 x 2k B Bayes] | [512 x 3 B RGB]
// Writes are atomic (core/paths.hpp). Loading a truncated, corrupt or other-version file throws
// semap::Error naming the file.
#include <filesystem>

#include "semap/tsdf/tsdf_map.hpp"

namespace semap {

constexpr uint32_t kMapFormatVersion = 1;

void save_map(const TsdfMap& map, const std::filesystem::path& path);
/// `base` supplies the run-time settings the file does not fix (integrator, threads, ranges);
/// voxel size, weights and layers come from the file.
TsdfMap load_map(const std::filesystem::path& path, const TsdfConfig& base = TsdfConfig{});

}  // namespace semap
