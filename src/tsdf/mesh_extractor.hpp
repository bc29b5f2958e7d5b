#pragma once
// Marching cubes over the zero crossing of the TSDF (METHODS.md B7), block by block. Each block
// keeps a cached mesh; extract() re-meshes only blocks changed since the last call (and the
// neighbours whose cubes read them), then welds vertices across blocks: a vertex is identified
// by its grid edge (lower voxel + axis), so both blocks sharing a face produce the same vertex.
// Vertex colour: class palette (core/labels.hpp class_colour) or the RGB layer; vertex label:
// Bayesian argmax when that layer is on, else the compact label byte.
#include <unordered_map>

#include "semap/core/point_cloud.hpp"
#include "semap/tsdf/tsdf_map.hpp"

namespace semap {

class MeshExtractor {
 public:
  explicit MeshExtractor(int threads = 0) : threads_(threads) {}
  /// Incremental: re-meshes dirty blocks only (clears their dirty flags).
  TriangleMesh extract(TsdfMap& map);
  /// Full re-mesh without touching caches or flags.
  TriangleMesh extract_full(const TsdfMap& map) const;
  size_t last_remeshed_blocks() const { return last_remeshed_; }
  void clear() { cache_.clear(); }

  struct BlockMesh {
    std::vector<uint64_t> edge_keys;  ///< global edge id of each vertex (welding key)
    std::vector<Eigen::Vector3f> positions;
    std::vector<ClassId> labels;
    std::vector<Rgb8> colours;
    std::vector<std::array<uint32_t, 3>> triangles;  ///< indices into this block's vertices
  };
  /// Marching cubes of the cubes whose lowest corner lies in block `b`.
  static BlockMesh mesh_block(const TsdfMap& map, const Block& b);

 private:
  static TriangleMesh assemble(const std::vector<const BlockMesh*>& meshes);
  int threads_;
  std::unordered_map<BlockIndex, BlockMesh, BlockHash> cache_;
  size_t last_remeshed_ = 0;
};

}  // namespace semap
