// dataset.yaml: read_dataset_yaml + apply_yaml_camera over a TUM preset.
#include "semap/core/error.hpp"
#include "fuzz/fuzz_util.hpp"
#include "io/dataset_layouts.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  semap::fuzz::write_seed("dataset.yaml", "format: tum\ncamera: {fx: 517.3, fy: 516.5, cx: 318.6, cy: 255.3, width: 640, "
                                          "height: 480, depth_scale: 5000}\n");
  semap::fuzz::write_seed("block.yaml", "format: 7scenes\ncamera:\n  fx: 585\n  fy: 585\n  depth_scale: 1000\n");
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = semap::fuzz::input_file("dataset.yaml", data, size);
  try {
    const auto yaml = semap::io_detail::read_dataset_yaml(path);
    semap::CameraModel camera = semap::tum_camera_preset(1);
    semap::io_detail::apply_yaml_camera(&yaml, camera);
  } catch (const semap::Error&) {
  }
  return 0;
}
