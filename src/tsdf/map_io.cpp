#include "tsdf/map_io.hpp"

#include "core/archive.hpp"

namespace semap {
namespace {

constexpr uint32_t kLabelLayer = 1, kBayesLayer = 2, kColourLayer = 4;

void put_header(ByteWriter& w, const TsdfMap& map) {
  const TsdfConfig& c = map.config();
  w.put(c.voxel_size);
  w.put(c.truncation_voxels);
  w.put(c.epsilon_voxels);
  w.put(c.weight_unit);
  w.put(c.weight_max);
  w.put(c.bayes_min_probability);
  w.put((c.label_layer ? kLabelLayer : 0u) | (c.bayes_layer ? kBayesLayer : 0u) | (c.colour_layer ? kColourLayer : 0u));
  w.put(static_cast<uint32_t>(c.bayes_top_k));
}

TsdfConfig get_header(ByteReader& r, const std::filesystem::path& path, TsdfConfig c) {
  c.voxel_size = r.get<double>();
  c.truncation_voxels = r.get<double>();
  c.epsilon_voxels = r.get<double>();
  c.weight_unit = r.get<double>();
  c.weight_max = r.get<double>();
  c.bayes_min_probability = r.get<double>();
  const uint32_t layers = r.get<uint32_t>();
  c.bayes_top_k = static_cast<int>(r.get<uint32_t>());
  c.label_layer = layers & kLabelLayer;
  c.bayes_layer = layers & kBayesLayer;
  c.colour_layer = layers & kColourLayer;
  try {
    c.validate();
  } catch (const Error& e) {
    throw Error(path, std::string("invalid map header: ") + e.what());
  }
  return c;
}

}  // namespace

std::string encode_tsdf_section(const TsdfMap& map) {
  const TsdfConfig& c = map.config();
  ByteWriter w;
  w.reserve(64 + map.num_blocks() * (12 + kBlockVoxels * map.bytes_per_voxel()));
  put_header(w, map);
  w.put(static_cast<uint64_t>(map.num_blocks()));
  const size_t bayes_bytes = static_cast<size_t>(kBlockVoxels) * map.bayes().bytes_per_voxel();
  for (const Block* b : map.sorted_blocks()) {
    w.put(b->index.x());
    w.put(b->index.y());
    w.put(b->index.z());
    w.put_bytes(b->voxels.data(), sizeof(TsdfVoxel) * kBlockVoxels);
    if (c.label_layer) w.put_bytes(b->label_confidence.get(), kBlockVoxels);
    if (c.bayes_layer) w.put_bytes(b->bayes.get(), bayes_bytes);
    if (c.colour_layer) w.put_bytes(b->colour.get(), sizeof(Rgb8) * kBlockVoxels);
  }
  return std::move(w.bytes());
}

TsdfMap decode_tsdf_section(std::string_view bytes, const std::filesystem::path& path, const TsdfConfig& base) {
  ByteReader r(bytes, path, kTsdfSection);
  const TsdfConfig c = get_header(r, path, base);
  TsdfMap map(c);
  const size_t bayes_bytes = static_cast<size_t>(kBlockVoxels) * map.bayes().bytes_per_voxel();
  const size_t n_blocks = r.get_count(12 + kBlockVoxels * map.bytes_per_voxel());
  for (size_t i = 0; i < n_blocks; ++i) {
    BlockIndex idx;
    idx.x() = r.get<int32_t>();
    idx.y() = r.get<int32_t>();
    idx.z() = r.get<int32_t>();
    if (map.find_block(idx)) r.fail("duplicate block");
    Block& b = map.allocate_block(idx);
    r.read(b.voxels.data(), sizeof(TsdfVoxel) * kBlockVoxels);
    if (c.label_layer) r.read(b.label_confidence.get(), kBlockVoxels);
    if (c.bayes_layer) r.read(b.bayes.get(), bayes_bytes);
    if (c.colour_layer) r.read(b.colour.get(), sizeof(Rgb8) * kBlockVoxels);
  }
  r.expect_end();
  return map;
}

void save_map(const TsdfMap& map, const std::filesystem::path& path) {
  write_map_archive(path, {{kTsdfSection, encode_tsdf_section(map)}});
}

TsdfMap load_map(const std::filesystem::path& path, const TsdfConfig& base) {
  const ArchiveSections sections = read_map_archive(path);
  return decode_tsdf_section(archive_section(sections, kTsdfSection, path), path, base);
}

}  // namespace semap
