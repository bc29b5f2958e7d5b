// map.semap loader (load_map: the archive container of core/archive.cpp and its tsdf
// section). The input is the file without its trailing checksum: the target appends the
// FNV-1a 64 of bytes [12, end) as write_map_archive does, so the fuzzer reaches the section
// table and block parsing instead of stopping at the checksum. Every
// 64th input is also loaded as-is (checksum/truncation paths).
#include <cstring>

#include "semap/core/error.hpp"
#include "fuzz/fuzz_util.hpp"
#include "tsdf/map_io.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  for (int variant = 0; variant < 2; ++variant) {
    semap::TsdfConfig c;
    c.voxel_size = 0.05;
    c.bayes_layer = variant == 1;
    c.colour_layer = variant == 1;
    semap::TsdfMap map(c);
    for (int b = 0; b < 2; ++b) {
      semap::Block& block = map.allocate_block(semap::BlockIndex(b, -1, 2));
      block.voxels[b * 7].set_sdf(0.25f);
      block.voxels[b * 7].weight_q = 3;
      block.voxels[b * 7].label = 5;
    }
    const auto path = semap::fuzz::scratch_dir() / "seed.semap";
    semap::save_map(map, path);
    const std::string bytes = semap::fuzz::read_bytes(path);
    semap::fuzz::write_seed("map" + std::to_string(variant) + ".semap", bytes.substr(0, bytes.size() - 8));
  }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = semap::fuzz::map_input_file(data, size);
  try {
    semap::load_map(path);
  } catch (const semap::Error&) {
  }
  return 0;
}
