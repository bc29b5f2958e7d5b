// TUM-style list files (rgb.txt, depth.txt, label.txt, 7-Scenes associations) and 3x4/4x4
// pose matrix files: io_detail::read_list and read_matrix_pose.
#include "semap/core/error.hpp"
#include "fuzz/fuzz_util.hpp"
#include "io/dataset_layouts.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  semap::fuzz::write_seed("rgb.txt", "# color images\n# timestamp filename\n1305031102.175304 rgb/1305031102.175304.png\n"
                                     "1305031102.211214 rgb/1305031102.211214.png\n");
  semap::fuzz::write_seed("assoc.txt", "0.0 frame-000000.color.png 0.0 frame-000000.depth.png\n0.033,a.png,0.034,b.png\r\n");
  semap::fuzz::write_seed("pose.txt", "1 0 0 0.5\n0 1 0 0\n0 0 1 -2\n0 0 0 1\n");
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = semap::fuzz::input_file("list.txt", data, size);
  try {
    semap::io_detail::read_list(path, size % 3 + 1);
  } catch (const semap::Error&) {
  }
  try {
    semap::io_detail::read_matrix_pose(path);
  } catch (const semap::Error&) {
  }
  return 0;
}
