// ROS1 bags (issue 44): open_dataset on a .bag - the checked pre-pass (io/rosbag_validate.cpp),
// then librosbag, the checked message deserialisers and the camera check - and every frame read.
#include "semap/core/error.hpp"
#include "semap/io/dataset.hpp"
#include "fuzz/fuzz_util.hpp"
#include "tests/io/test_rosbag_writer.hpp"

namespace {

/// Seeds: two-frame bags from the tests' rosbag writer, uncompressed and lz4, with raw and
/// compressed colour and a CameraInfo with distortion.
void write_bag_seeds() {
  using namespace semap::test;
  const auto dir = semap::fuzz::scratch_dir() / "seeds";
  std::filesystem::create_directories(dir);
  for (const bool lz4 : {false, true}) {
    const auto file = dir / (lz4 ? "seed_lz4.bag" : "seed.bag");
    {
      BagWriter bag(file, lz4);
      for (uint32_t n = 1; n <= 2; ++n) {
        bag.write(RosImage{"/c/image", {n, 0}, "rgb8", 8, 8, 24, false, std::vector<uint8_t>(192, 40)});
        bag.write(RosImage{"/d/image", {n, 0}, "16UC1", 8, 8, 16, false, std::vector<uint8_t>(128, 7)});
        bag.write(RosCameraInfo{"/d/camera_info", {n, 0}, 8, 8, {8, 0, 4, 0, 8, 4, 0, 0, 1}, {0.1, 0, 0, 0, 0}});
        bag.write_imu("/imu", {n, 0});
      }
    }
    semap::fuzz::write_seed(file.filename().string(), semap::fuzz::read_bytes(file));
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  write_bag_seeds();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = semap::fuzz::input_file("input.bag", data, size);
  try {
    const auto reader = semap::open_dataset(path);
    for (size_t i = 0; i < reader->size() && i < 8; ++i) reader->load(i);
  } catch (const semap::Error&) {
  }
  return 0;
}
