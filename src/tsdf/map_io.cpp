#include "tsdf/map_io.hpp"

#include <cstring>
#include <fstream>
#include <sstream>

#include "semap/core/error.hpp"
#include "core/paths.hpp"

namespace semap {
namespace {

constexpr char kMagic[8] = {'S', 'E', 'M', 'A', 'P', 'M', 'A', 'P'};

uint64_t fnv1a(const char* data, size_t n) {
  uint64_t h = 1469598103934665603ULL;
  for (size_t i = 0; i < n; ++i) {
    h ^= static_cast<uint8_t>(data[i]);
    h *= 1099511628211ULL;
  }
  return h;
}

template <class T>
void put(std::string& out, const T& v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof(T));
}

struct Reader {
  const std::string& bytes;
  size_t pos;
  const std::filesystem::path& path;
  template <class T>
  T get() {
    T v;
    read(&v, sizeof(T));
    return v;
  }
  void read(void* dst, size_t n) {
    if (pos + n > bytes.size()) throw Error(path, "truncated map file");
    std::memcpy(dst, bytes.data() + pos, n);
    pos += n;
  }
};

}  // namespace

void save_map(const TsdfMap& map, const std::filesystem::path& path) {
  const TsdfConfig& c = map.config();
  std::string header;
  put(header, c.voxel_size);
  put(header, c.truncation_voxels);
  put(header, c.epsilon_voxels);
  put(header, c.weight_unit);
  put(header, c.weight_max);
  put(header, c.bayes_min_probability);
  const uint32_t layers = (c.label_layer ? 1u : 0u) | (c.bayes_layer ? 2u : 0u) | (c.colour_layer ? 4u : 0u);
  put(header, layers);
  put(header, static_cast<uint32_t>(c.bayes_top_k));
  put(header, static_cast<uint64_t>(map.num_blocks()));
  std::string out(kMagic, 8);
  put(out, kMapFormatVersion);
  put(out, static_cast<uint32_t>(header.size()));
  const size_t checked_from = out.size();
  out += header;
  const size_t bayes_bytes = static_cast<size_t>(kBlockVoxels) * map.bayes().bytes_per_voxel();
  out.reserve(out.size() + map.num_blocks() * (12 + kBlockVoxels * map.bytes_per_voxel()) + 8);
  for (const Block* b : map.sorted_blocks()) {
    put(out, b->index.x());
    put(out, b->index.y());
    put(out, b->index.z());
    out.append(reinterpret_cast<const char*>(b->voxels.data()), sizeof(TsdfVoxel) * kBlockVoxels);
    if (c.label_layer) out.append(reinterpret_cast<const char*>(b->label_confidence.get()), kBlockVoxels);
    if (c.bayes_layer) out.append(reinterpret_cast<const char*>(b->bayes.get()), bayes_bytes);
    if (c.colour_layer) out.append(reinterpret_cast<const char*>(b->colour.get()), sizeof(Rgb8) * kBlockVoxels);
  }
  put(out, fnv1a(out.data() + checked_from, out.size() - checked_from));
  write_file_atomic(path, out);
}

TsdfMap load_map(const std::filesystem::path& path, const TsdfConfig& base) {
  const std::string bytes = read_regular_file(path, kMaxMeshFileBytes, "map file");
  if (bytes.size() < 8 + 8 + 8 || std::memcmp(bytes.data(), kMagic, 8) != 0)
    throw Error(path, "not a semap map file (bad magic or truncated)");
  Reader r{bytes, 8, path};
  const uint32_t version = r.get<uint32_t>();
  if (version != kMapFormatVersion)
    throw Error(path, "map format version " + std::to_string(version) + " (this build reads " +
                          std::to_string(kMapFormatVersion) + ")");
  const uint32_t header_bytes = r.get<uint32_t>();
  const size_t checked_from = r.pos;
  if (bytes.size() < checked_from + 8) throw Error(path, "truncated map file");
  uint64_t stored_sum;
  std::memcpy(&stored_sum, bytes.data() + bytes.size() - 8, 8);
  if (fnv1a(bytes.data() + checked_from, bytes.size() - 8 - checked_from) != stored_sum)
    throw Error(path, "checksum mismatch (corrupt or truncated map file)");
  TsdfConfig c = base;
  c.voxel_size = r.get<double>();
  c.truncation_voxels = r.get<double>();
  c.epsilon_voxels = r.get<double>();
  c.weight_unit = r.get<double>();
  c.weight_max = r.get<double>();
  c.bayes_min_probability = r.get<double>();
  const uint32_t layers = r.get<uint32_t>();
  c.bayes_top_k = static_cast<int>(r.get<uint32_t>());
  const uint64_t n_blocks = r.get<uint64_t>();
  if (r.pos != checked_from + header_bytes) throw Error(path, "unexpected header size");
  c.label_layer = layers & 1u;
  c.bayes_layer = layers & 2u;
  c.colour_layer = layers & 4u;
  try {
    c.validate();
  } catch (const Error& e) {
    throw Error(path, std::string("invalid map header: ") + e.what());
  }
  TsdfMap map(c);
  const size_t bayes_bytes = static_cast<size_t>(kBlockVoxels) * map.bayes().bytes_per_voxel();
  const size_t block_bytes = 12 + kBlockVoxels * map.bytes_per_voxel();
  if (n_blocks > (bytes.size() - r.pos) / block_bytes) throw Error(path, "truncated map file (block count)");
  for (uint64_t i = 0; i < n_blocks; ++i) {
    BlockIndex idx;
    idx.x() = r.get<int32_t>();
    idx.y() = r.get<int32_t>();
    idx.z() = r.get<int32_t>();
    if (map.find_block(idx)) throw Error(path, "duplicate block in map file");
    Block& b = map.allocate_block(idx);
    r.read(b.voxels.data(), sizeof(TsdfVoxel) * kBlockVoxels);
    if (c.label_layer) r.read(b.label_confidence.get(), kBlockVoxels);
    if (c.bayes_layer) r.read(b.bayes.get(), bayes_bytes);
    if (c.colour_layer) r.read(b.colour.get(), sizeof(Rgb8) * kBlockVoxels);
  }
  if (r.pos != bytes.size() - 8) throw Error(path, "trailing bytes after the last block");
  return map;
}

}  // namespace semap
