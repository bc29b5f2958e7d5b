// CDR (issue 40): the ROS 2 message decoders of io_detail::ros2_msgs (Image, CompressedImage,
// CameraInfo, image headers) on arbitrary bytes.
#include "semap/core/error.hpp"
#include "fuzz/fuzz_util.hpp"
#include "io/cdr_reader.hpp"
#include "tests/io/rosbag2_writer.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  using namespace semap::test;
  const auto seed = [](const std::string& name, const std::vector<uint8_t>& b) { semap::fuzz::write_seed(name, std::string(b.begin(), b.end())); };
  seed("image.cdr", cdr_image(RosImage{"/c", {1, 2}, "rgb8", 2, 2, 6, false, std::vector<uint8_t>(12, 9)}));
  seed("compressed.cdr", cdr_compressed_image(RosCompressedImage{"/c", {1, 2}, "16UC1; compressedDepth png", {1, 2, 3}}));
  seed("info.cdr", cdr_camera_info(RosCameraInfo{"/i", {1, 2}, 4, 3, {5, 0, 2, 0, 5, 1.5, 0, 0, 1}, {0.1, -0.2, 0, 0, 0.01}}));
  seed("imu.cdr", cdr_imu({3, 4}));
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::span<const uint8_t> bytes(data, size);
  namespace m = semap::io_detail::ros2_msgs;
  const auto attempt = [](auto&& f) {
    try {
      f();
    } catch (const semap::Error&) {
    }
  };
  attempt([&] { m::image(bytes, "fuzz.cdr"); });
  attempt([&] { m::compressed_image(bytes, "fuzz.cdr"); });
  attempt([&] { m::camera_info(bytes, "fuzz.cdr"); });
  attempt([&] { m::image_meta(bytes, size % 2 == 0, "fuzz.cdr"); });
  return 0;
}
