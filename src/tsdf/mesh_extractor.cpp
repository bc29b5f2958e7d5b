#include "tsdf/mesh_extractor.hpp"

#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>

#include "tsdf/mc_tables.hpp"
#include "tsdf/voxel_label.hpp"

namespace semap {
namespace {

constexpr int kN = kBlockSide + 1;  // neighbourhood side: the block + one layer of +x/+y/+z
constexpr int kCorner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
constexpr int kEdge[12][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6}, {6, 7}, {7, 4}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};

struct Sample {
  float sdf = 0;
  bool valid = false;
  ClassId label = 0;
  Rgb8 colour;
};

constexpr int kEdgeBits = 20;
constexpr int32_t kEdgeOffset = 1 << (kEdgeBits - 1);
uint64_t edge_key(const Eigen::Vector3i& v, int axis) {
  const uint64_t m = (1u << kEdgeBits) - 1;
  return (static_cast<uint64_t>(v.x() + kEdgeOffset) & m) | ((static_cast<uint64_t>(v.y() + kEdgeOffset) & m) << kEdgeBits) |
         ((static_cast<uint64_t>(v.z() + kEdgeOffset) & m) << (2 * kEdgeBits)) | (static_cast<uint64_t>(axis) << 60);
}

bool block_less(const BlockIndex& a, const BlockIndex& b) {
  if (a.z() != b.z()) return a.z() < b.z();
  if (a.y() != b.y()) return a.y() < b.y();
  return a.x() < b.x();
}

}  // namespace

MeshExtractor::BlockMesh MeshExtractor::mesh_block(const TsdfMap& map, const Block& block) {
  const bool rgb = map.config().mesh_colour == MeshColour::rgb && map.has_colour_layer();
  const float min_weight = static_cast<float>(map.config().mesh_min_weight);
  const VoxelLabelRule label_rule(map);
  // Gather the 9^3 neighbourhood (this block plus the first layer of its +x/+y/+z neighbours).
  std::array<Sample, kN * kN * kN> samples;
  const Block* neighbours[2][2][2];
  for (int dz = 0; dz < 2; ++dz)
    for (int dy = 0; dy < 2; ++dy)
      for (int dx = 0; dx < 2; ++dx)
        neighbours[dz][dy][dx] = (dx | dy | dz) ? map.find_block(block.index + BlockIndex(dx, dy, dz)) : &block;
  for (int z = 0; z < kN; ++z)
    for (int y = 0; y < kN; ++y)
      for (int x = 0; x < kN; ++x) {
        const Block* b = neighbours[z >> 3][y >> 3][x >> 3];
        Sample& s = samples[x + kN * (y + kN * z)];
        if (!b) continue;
        const int li = (x & 7) + 8 * ((y & 7) + 8 * (z & 7));
        const TsdfVoxel& v = b->voxels[li];
        if (v.weight_q == 0 || map.weights().decode(v.weight_q) <= min_weight) continue;
        s.valid = true;
        s.sdf = v.sdf();
        // Labels with too little evidence (e.g. seen in one frame) are shown as unlabelled.
        s.label = label_rule.label(*b, li);
        s.colour = rgb ? b->colour[li] : class_colour(s.label);
      }
  BlockMesh mesh;
  std::array<int32_t, kN * kN * kN * 3> edge_vertex;
  edge_vertex.fill(-1);
  const Eigen::Vector3i base = block.index * kBlockSide;
  const float s = map.voxel_size();
  for (int z = 0; z < kBlockSide; ++z)
    for (int y = 0; y < kBlockSide; ++y)
      for (int x = 0; x < kBlockSide; ++x) {
        const Sample* corner[8];
        int cube = 0;
        bool ok = true;
        for (int i = 0; i < 8 && ok; ++i) {
          corner[i] = &samples[(x + kCorner[i][0]) + kN * ((y + kCorner[i][1]) + kN * (z + kCorner[i][2]))];
          ok = corner[i]->valid;
          if (corner[i]->sdf < 0) cube |= 1 << i;
        }
        if (!ok || mc::edgeTable[cube] == 0) continue;
        int32_t vertex_of_edge[12];
        for (int e = 0; e < 12; ++e) {
          if (!(mc::edgeTable[cube] & (1 << e))) continue;
          // Canonical direction: from the lower to the upper endpoint along the edge's axis.
          int c0 = kEdge[e][0], c1 = kEdge[e][1];
          int axis = 0;
          for (int a = 0; a < 3; ++a)
            if (kCorner[c0][a] != kCorner[c1][a]) axis = a;
          if (kCorner[c0][axis] > kCorner[c1][axis]) std::swap(c0, c1);
          const Eigen::Vector3i lo(x + kCorner[c0][0], y + kCorner[c0][1], z + kCorner[c0][2]);
          int32_t& slot = edge_vertex[((lo.x() + kN * (lo.y() + kN * lo.z())) * 3) + axis];
          if (slot < 0) {
            const Sample& a = *corner[c0];
            const Sample& b = *corner[c1];
            const float t = a.sdf / (a.sdf - b.sdf);
            Eigen::Vector3f p = ((base + lo).cast<float>().array() + 0.5f) * s;
            p[axis] += t * s;
            // Label of the edge's corner nearest to the surface; when that one has too little
            // evidence to show a label, the other corner of the same edge (same surface patch).
            const bool a_nearer = std::fabs(a.sdf) <= std::fabs(b.sdf);
            const Sample& closer = a_nearer ? a : b;
            const Sample& farther = a_nearer ? b : a;
            const Sample& corner = closer.label != 0 ? closer : farther;
            slot = static_cast<int32_t>(mesh.positions.size());
            mesh.positions.push_back(p);
            mesh.edge_keys.push_back(edge_key(base + lo, axis));
            mesh.labels.push_back(corner.label);
            if (rgb) {
              auto mix = [&](uint8_t ca, uint8_t cb) { return static_cast<uint8_t>(std::lround(ca + t * (cb - ca))); };
              mesh.colours.push_back(Rgb8{mix(a.colour.r, b.colour.r), mix(a.colour.g, b.colour.g), mix(a.colour.b, b.colour.b)});
            } else {
              mesh.colours.push_back(corner.colour);
            }
          }
          vertex_of_edge[e] = slot;
        }
        for (int i = 0; mc::triTable[cube][i] != -1; i += 3) {
          // Reversed winding: normals point to positive sdf (free space, towards the camera).
          mesh.triangles.push_back({static_cast<uint32_t>(vertex_of_edge[mc::triTable[cube][i]]),
                                    static_cast<uint32_t>(vertex_of_edge[mc::triTable[cube][i + 2]]),
                                    static_cast<uint32_t>(vertex_of_edge[mc::triTable[cube][i + 1]])});
        }
      }
  return mesh;
}

TriangleMesh MeshExtractor::assemble(const std::vector<const BlockMesh*>& meshes) {
  TriangleMesh out;
  size_t n_vertices = 0, n_triangles = 0;
  for (const BlockMesh* m : meshes) {
    n_vertices += m->positions.size();
    n_triangles += m->triangles.size();
  }
  std::unordered_map<uint64_t, uint32_t> welded;
  welded.reserve(n_vertices);
  out.vertices.points.reserve(n_vertices);
  out.vertices.colours.reserve(n_vertices);
  out.vertices.labels.reserve(n_vertices);
  out.triangles.reserve(n_triangles);
  std::vector<uint32_t> remap;
  for (const BlockMesh* m : meshes) {
    remap.resize(m->positions.size());
    for (size_t i = 0; i < m->positions.size(); ++i) {
      auto [it, inserted] = welded.try_emplace(m->edge_keys[i], static_cast<uint32_t>(out.vertices.points.size()));
      if (inserted) {
        out.vertices.points.push_back(m->positions[i]);
        out.vertices.colours.push_back(m->colours[i]);
        out.vertices.labels.push_back(m->labels[i]);
      }
      remap[i] = it->second;
    }
    for (const auto& t : m->triangles) {
      const std::array<uint32_t, 3> g{remap[t[0]], remap[t[1]], remap[t[2]]};
      if (g[0] == g[1] || g[1] == g[2] || g[0] == g[2]) continue;  // degenerate (vertex on a corner)
      out.triangles.push_back(g);
    }
  }
  return out;
}

TriangleMesh MeshExtractor::extract(TsdfMap& map) {
  // Blocks to re-mesh: dirty ones, and the -x/-y/-z neighbours whose cubes read them.
  std::vector<BlockIndex> todo;
  auto add_with_neighbours = [&](const BlockIndex& b) {
    for (int dz = 0; dz < 2; ++dz)
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
          const BlockIndex n = b - BlockIndex(dx, dy, dz);
          if (map.find_block(n)) todo.push_back(n);
        }
  };
  for (const BlockIndex& b : map.take_removed_blocks()) {
    cache_.erase(b);
    add_with_neighbours(b);
  }
  for (const auto& b : map.blocks())
    if (b->mesh_dirty) add_with_neighbours(b->index);
  std::sort(todo.begin(), todo.end(), block_less);
  todo.erase(std::unique(todo.begin(), todo.end()), todo.end());
  std::vector<BlockMesh> fresh(todo.size());
  tbb::task_arena arena(threads_ > 0 ? threads_ : tbb::info::default_concurrency());
  arena.execute([&] {
    tbb::parallel_for(size_t{0}, todo.size(), [&](size_t i) { fresh[i] = mesh_block(map, *map.find_block(todo[i])); });
  });
  for (size_t i = 0; i < todo.size(); ++i) cache_[todo[i]] = std::move(fresh[i]);
  for (const auto& b : map.blocks()) b->mesh_dirty = false;
  last_remeshed_ = todo.size();
  std::vector<const Block*> order = map.sorted_blocks();
  std::vector<const BlockMesh*> meshes;
  meshes.reserve(order.size());
  for (const Block* b : order) {
    auto it = cache_.find(b->index);
    if (it != cache_.end()) meshes.push_back(&it->second);
  }
  return assemble(meshes);
}

TriangleMesh MeshExtractor::extract_full(const TsdfMap& map) const {
  std::vector<const Block*> order = map.sorted_blocks();
  std::vector<BlockMesh> meshes(order.size());
  tbb::task_arena arena(threads_ > 0 ? threads_ : tbb::info::default_concurrency());
  arena.execute([&] {
    tbb::parallel_for(size_t{0}, order.size(), [&](size_t i) { meshes[i] = mesh_block(map, *order[i]); });
  });
  std::vector<const BlockMesh*> ptrs;
  for (const BlockMesh& m : meshes) ptrs.push_back(&m);
  return assemble(ptrs);
}

}  // namespace semap
