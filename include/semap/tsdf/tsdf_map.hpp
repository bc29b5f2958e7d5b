#pragma once
// Sparse voxel-hashed TSDF map (METHODS.md B3, B4): 8x8x8 blocks of 4-byte voxels in a spatial
// hash, allocated only near observed surfaces, with optional per-voxel layers (compact label
// vote, Bayesian top-k classes, RGB).
#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

#include "semap/tsdf/tsdf_config.hpp"
#include "semap/tsdf/voxel.hpp"

namespace semap {

constexpr int kBlockSide = 8;  ///< eta of B4
constexpr int kBlockVoxels = kBlockSide * kBlockSide * kBlockSide;

using BlockIndex = Eigen::Vector3i;
using VoxelIndex = Eigen::Vector3i;  ///< global voxel index floor(p / s)

/// METHODS B4: H(x, y, z) = (x p1 xor y p2 xor z p3) mod n.
struct BlockHash {
  size_t operator()(const BlockIndex& b) const {
    return static_cast<size_t>((static_cast<uint32_t>(b.x()) * 73856093u) ^
                               (static_cast<uint32_t>(b.y()) * 19349669u) ^
                               (static_cast<uint32_t>(b.z()) * 83492791u));
  }
};

inline int floor_div(int a, int b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }
inline BlockIndex block_of_voxel(const VoxelIndex& v) {
  return {v.x() >> 3, v.y() >> 3, v.z() >> 3};  // arithmetic shift = floor division by 8
}
inline int local_index(const VoxelIndex& v) { return (v.x() & 7) + 8 * (v.y() & 7) + 64 * (v.z() & 7); }

struct Block {
  BlockIndex index;
  std::array<TsdfVoxel, kBlockVoxels> voxels{};
  std::unique_ptr<uint8_t[]> label_confidence;  ///< kBlockVoxels, compact vote confidence (label_layer)
  std::unique_ptr<uint8_t[]> bayes;             ///< kBlockVoxels * 2k bytes (bayes_layer)
  std::unique_ptr<Rgb8[]> colour;               ///< kBlockVoxels (colour_layer)
  bool mesh_dirty = true;                       ///< changed since the last mesh extraction
  uint32_t frame_stamp = 0;                     ///< integrator scratch: last frame that touched it
  int32_t frame_slot = -1;                      ///< integrator scratch: index among touched blocks
};

/// Open-addressing (linear probing, B4 hash, backward-shift deletion) map BlockIndex -> slot.
/// Measured against std::unordered_map with the same hash in bench_tsdf.
class BlockHashTable {
 public:
  BlockHashTable() { rehash(1024); }
  /// Slot of `key` or -1.
  int32_t find(const BlockIndex& key) const {
    size_t i = BlockHash{}(key) & mask_;
    while (true) {
      const Entry& e = entries_[i];
      if (e.slot < 0) return -1;
      if (e.key == key) return e.slot;
      i = (i + 1) & mask_;
    }
  }
  /// Inserts key -> slot (key must be absent).
  void insert(const BlockIndex& key, int32_t slot);
  void erase(const BlockIndex& key);
  void set_slot(const BlockIndex& key, int32_t slot);
  size_t size() const { return size_; }
  size_t memory_bytes() const { return entries_.size() * sizeof(Entry); }

 private:
  struct Entry {
    BlockIndex key{0, 0, 0};
    int32_t slot = -1;
  };
  void rehash(size_t capacity);
  std::vector<Entry> entries_;
  size_t mask_ = 0, size_ = 0;
};

class TsdfMap {
 public:
  explicit TsdfMap(const TsdfConfig& config);

  const TsdfConfig& config() const { return config_; }
  float voxel_size() const { return voxel_size_; }
  float block_size() const { return voxel_size_ * kBlockSide; }
  const WeightQuantizer& weights() const { return weights_; }
  const BayesLayerCodec& bayes() const { return bayes_; }
  bool has_label_layer() const { return config_.label_layer; }
  bool has_bayes_layer() const { return config_.bayes_layer; }
  bool has_colour_layer() const { return config_.colour_layer; }

  size_t num_blocks() const { return blocks_.size(); }
  Block* find_block(const BlockIndex& b) {
    const int32_t s = hash_.find(b);
    return s < 0 ? nullptr : blocks_[s].get();
  }
  const Block* find_block(const BlockIndex& b) const {
    const int32_t s = hash_.find(b);
    return s < 0 ? nullptr : blocks_[s].get();
  }
  /// Finds or allocates (with the configured layers) the block.
  Block& allocate_block(const BlockIndex& b);
  void remove_block(const BlockIndex& b);
  /// Frees blocks whose centre is farther than `distance` from `position` (long runs).
  size_t remove_blocks_beyond(const Eigen::Vector3f& position, float distance);
  /// Blocks in storage order (stable between calls without allocation/removal).
  const std::vector<std::unique_ptr<Block>>& blocks() const { return blocks_; }
  /// Blocks sorted by index (deterministic order for meshing and saving).
  std::vector<const Block*> sorted_blocks() const;
  /// A fresh stamp per integrated frame (blocks remember the frame that touched them last).
  uint32_t next_frame_stamp() { return ++frame_stamp_; }
  /// Keys of blocks removed since the last call (the mesher drops their caches).
  std::vector<BlockIndex> take_removed_blocks();

  const TsdfVoxel* find_voxel(const VoxelIndex& v) const {
    const Block* b = find_block(block_of_voxel(v));
    return b ? &b->voxels[local_index(v)] : nullptr;
  }
  VoxelIndex voxel_of_point(const Eigen::Vector3f& p) const {
    return (p / voxel_size_).array().floor().cast<int>();
  }
  Eigen::Vector3f voxel_centre(const VoxelIndex& v) const { return (v.cast<float>().array() + 0.5f) * voxel_size_; }
  /// Interpolation-free sdf lookup (nullopt-like: returns false when unobserved).
  bool sdf_at(const VoxelIndex& v, float& sdf) const {
    const TsdfVoxel* voxel = find_voxel(v);
    if (!voxel || voxel->weight_q == 0) return false;
    sdf = voxel->sdf();
    return true;
  }

  /// Bytes of one voxel with every enabled layer (4 core + 1 vote + 2k Bayes + 3 colour).
  size_t bytes_per_voxel() const;
  /// Memory held by blocks and the hash table.
  size_t memory_bytes() const;
  size_t observed_voxels() const;

  /// Exact equality of configuration-relevant fields, blocks and every layer.
  bool operator==(const TsdfMap& other) const;

 private:
  TsdfConfig config_;
  float voxel_size_;
  WeightQuantizer weights_;
  BayesLayerCodec bayes_;
  std::vector<std::unique_ptr<Block>> blocks_;
  BlockHashTable hash_;
  std::vector<BlockIndex> removed_;
  uint32_t frame_stamp_ = 0;
};

}  // namespace semap
