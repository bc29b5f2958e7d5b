#pragma once
// PLY read/write for point clouds and triangle meshes. Vertex properties: x y z (float),
// optional nx ny nz, red green blue (uchar), label (uchar, project class id), instance (uint).
// Writes binary little endian; reads binary little endian and ASCII (Open3D/MeshLab/PCL files).
#include <filesystem>
#include <string>

#include "semap/core/point_cloud.hpp"

namespace semap {

void write_ply(const std::filesystem::path& path, const PointCloud& cloud);
void write_ply(const std::filesystem::path& path, const TriangleMesh& mesh);
/// The bytes write_ply writes (`name` only for messages), e.g. to serve a mesh from memory.
std::string encode_ply(const TriangleMesh& mesh, const std::filesystem::path& name);
/// Reads vertices (and faces, if any). Throws semap::Error naming the file for malformed
/// headers, truncated data, unsupported formats.
TriangleMesh read_ply(const std::filesystem::path& path);
/// Same, from the file's bytes in memory (`source` names it in messages; fuzz targets use it).
TriangleMesh parse_ply(const std::string& bytes, const std::string& source);

}  // namespace semap
