#include "semap/tsdf/tsdf_map.hpp"

#include <algorithm>
#include <cstring>
#include <utility>

namespace semap {

void BlockHashTable::rehash(size_t capacity) {
  std::vector<Entry> old = std::move(entries_);
  entries_.assign(capacity, Entry{});
  mask_ = capacity - 1;
  size_ = 0;
  for (const Entry& e : old)
    if (e.slot >= 0) insert(e.key, e.slot);
}

void BlockHashTable::insert(const BlockIndex& key, int32_t slot) {
  if ((size_ + 1) * 2 > entries_.size()) rehash(entries_.size() * 2);  // load factor <= 0.5
  size_t i = BlockHash{}(key) & mask_;
  while (entries_[i].slot >= 0) i = (i + 1) & mask_;
  entries_[i].key = key;
  entries_[i].slot = slot;
  ++size_;
}

void BlockHashTable::set_slot(const BlockIndex& key, int32_t slot) {
  size_t i = BlockHash{}(key) & mask_;
  while (entries_[i].slot >= 0) {
    if (entries_[i].key == key) {
      entries_[i].slot = slot;
      return;
    }
    i = (i + 1) & mask_;
  }
}

void BlockHashTable::erase(const BlockIndex& key) {
  size_t i = BlockHash{}(key) & mask_;
  while (true) {
    if (entries_[i].slot < 0) return;
    if (entries_[i].key == key) break;
    i = (i + 1) & mask_;
  }
  // Backward-shift deletion keeps probe chains intact without tombstones.
  size_t hole = i;
  size_t j = (i + 1) & mask_;
  while (entries_[j].slot >= 0) {
    const size_t home = BlockHash{}(entries_[j].key) & mask_;
    const bool movable = ((j - home) & mask_) >= ((j - hole) & mask_);
    if (movable) {
      entries_[hole] = entries_[j];
      hole = j;
    }
    j = (j + 1) & mask_;
  }
  entries_[hole] = Entry{};
  --size_;
}

TsdfMap::TsdfMap(const TsdfConfig& config)
    : config_(config),
      voxel_size_(static_cast<float>(config.voxel_size)),
      weights_(config.weight_unit, config.weight_max),
      bayes_(config.bayes_top_k, config.bayes_min_probability) {
  config_.validate();
}

Block& TsdfMap::allocate_block(const BlockIndex& b) {
  const int32_t s = hash_.find(b);
  if (s >= 0) return *blocks_[s];
  auto block = std::make_unique<Block>();
  block->index = b;
  for (TsdfVoxel& v : block->voxels) v.set_sdf(static_cast<float>(config_.truncation()));
  if (config_.label_layer) block->label_confidence = std::make_unique<uint8_t[]>(kBlockVoxels);
  if (config_.bayes_layer) {
    const size_t n = static_cast<size_t>(kBlockVoxels) * bayes_.bytes_per_voxel();
    block->bayes = std::make_unique<uint8_t[]>(n);
    for (size_t i = 0; i < n; i += 2) block->bayes[i + 1] = 255;  // empty slots
  }
  if (config_.colour_layer) block->colour = std::make_unique<Rgb8[]>(kBlockVoxels);
  hash_.insert(b, static_cast<int32_t>(blocks_.size()));
  blocks_.push_back(std::move(block));
  return *blocks_.back();
}

void TsdfMap::remove_block(const BlockIndex& b) {
  const int32_t s = hash_.find(b);
  if (s < 0) return;
  hash_.erase(b);
  removed_.push_back(b);
  const int32_t last = static_cast<int32_t>(blocks_.size()) - 1;
  if (s != last) {
    blocks_[s] = std::move(blocks_[last]);
    hash_.set_slot(blocks_[s]->index, s);
  }
  blocks_.pop_back();
}

size_t TsdfMap::remove_blocks_beyond(const Eigen::Vector3f& position, float distance) {
  std::vector<BlockIndex> far;
  const float half = 0.5f * block_size();
  for (const auto& b : blocks_) {
    const Eigen::Vector3f centre = b->index.cast<float>() * block_size() + Eigen::Vector3f::Constant(half);
    if ((centre - position).norm() > distance) far.push_back(b->index);
  }
  for (const BlockIndex& b : far) remove_block(b);
  return far.size();
}

static bool block_less(const BlockIndex& a, const BlockIndex& b) {
  if (a.z() != b.z()) return a.z() < b.z();
  if (a.y() != b.y()) return a.y() < b.y();
  return a.x() < b.x();
}

std::vector<const Block*> TsdfMap::sorted_blocks() const {
  std::vector<const Block*> out;
  out.reserve(blocks_.size());
  for (const auto& b : blocks_) out.push_back(b.get());
  std::sort(out.begin(), out.end(), [](const Block* a, const Block* b) { return block_less(a->index, b->index); });
  return out;
}

std::vector<BlockIndex> TsdfMap::take_removed_blocks() { return std::exchange(removed_, {}); }

size_t TsdfMap::bytes_per_voxel() const {
  size_t bytes = sizeof(TsdfVoxel);
  if (config_.label_layer) bytes += 1;
  if (config_.bayes_layer) bytes += bayes_.bytes_per_voxel();
  if (config_.colour_layer) bytes += sizeof(Rgb8);
  return bytes;
}

size_t TsdfMap::memory_bytes() const {
  return blocks_.size() * (sizeof(Block) + kBlockVoxels * (bytes_per_voxel() - sizeof(TsdfVoxel))) +
         hash_.memory_bytes() + blocks_.capacity() * sizeof(void*);
}

size_t TsdfMap::observed_voxels() const {
  size_t n = 0;
  for (const auto& b : blocks_)
    for (const TsdfVoxel& v : b->voxels) n += v.weight_q > 0;
  return n;
}

bool TsdfMap::operator==(const TsdfMap& other) const {
  if (voxel_size_ != other.voxel_size_ || bytes_per_voxel() != other.bytes_per_voxel() ||
      blocks_.size() != other.blocks_.size() || config_.bayes_top_k != other.config_.bayes_top_k)
    return false;
  for (const auto& b : blocks_) {
    const Block* o = other.find_block(b->index);
    if (!o || b->voxels != o->voxels) return false;
    if (config_.label_layer &&
        std::memcmp(b->label_confidence.get(), o->label_confidence.get(), kBlockVoxels) != 0)
      return false;
    if (config_.bayes_layer &&
        std::memcmp(b->bayes.get(), o->bayes.get(), static_cast<size_t>(kBlockVoxels) * bayes_.bytes_per_voxel()) != 0)
      return false;
    if (config_.colour_layer && !std::equal(b->colour.get(), b->colour.get() + kBlockVoxels, o->colour.get()))
      return false;
  }
  return true;
}

}  // namespace semap
