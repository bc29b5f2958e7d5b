#pragma once
// The TSDF section of map.semap (core/archive.hpp holds the container):
//   f64 voxel_size, f64 truncation_voxels, f64 epsilon_voxels, f64 weight_unit, f64 weight_max,
//   f64 bayes_min_probability, u32 layers (1 label, 2 bayes, 4 colour), u32 bayes_top_k,
//   u64 block count, then per block (sorted by z, y, x): i32 x y z | 512 x 4 B voxels
//   | [512 B vote] | [512 x 2k B Bayes] | [512 x 3 B RGB]
// save_map / load_map write and read a map.semap holding this section (a Mapper's map.semap
// holds the other stages' sections beside it). A truncated, corrupt or other-version file
// throws semap::Error naming the file.
#include <filesystem>
#include <string>
#include <string_view>

#include "semap/tsdf/tsdf_map.hpp"

namespace semap {

inline constexpr const char* kTsdfSection = "tsdf";

std::string encode_tsdf_section(const TsdfMap& map);
/// `base` supplies the run-time settings the file does not fix (integrator, threads, ranges);
/// voxel size, weights and layers come from the file. `path` names the file in errors.
TsdfMap decode_tsdf_section(std::string_view bytes, const std::filesystem::path& path,
                            const TsdfConfig& base = TsdfConfig{});

void save_map(const TsdfMap& map, const std::filesystem::path& path);
TsdfMap load_map(const std::filesystem::path& path, const TsdfConfig& base = TsdfConfig{});

}  // namespace semap
