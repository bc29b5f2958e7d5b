// The one config file (`semap run --config`, `semap config --check`): load_config_string over
// every section of SemapConfig, then validate(), as load_semap_config does.
#include "semap/core/error.hpp"
#include "fuzz/fuzz_util.hpp"
#include "semap/io/config_loader.hpp"
#include "semap/pipeline/semap_config.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  semap::SemapConfig defaults;
  semap::fuzz::write_seed("default.yaml", semap::dump_config([&](semap::ParamVisitor& v) { defaults.visit(v); }));
  semap::fuzz::write_seed("small.yaml", "pipeline: {threads: 1}\ntsdf:\n  voxel_size: 0.02\n  bayes_layer: true\n"
                                        "segmentation:\n  segmenter: groundtruth\n");
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  semap::SemapConfig config;
  try {
    semap::load_config_string(std::string(reinterpret_cast<const char*>(data), size), "fuzz.yaml",
                              [&](semap::ParamVisitor& v) { config.visit(v); });
    config.validate();
  } catch (const semap::Error&) {
  }
  return 0;
}
