// MCAP files (issue 40): io_detail::McapReader (summary or linear scan, chunk decompression)
// and every message it indexes read back and decoded as a ROS 2 image header (CDR).
#include "semap/core/error.hpp"
#include "fuzz/fuzz_util.hpp"
#include "io/cdr_reader.hpp"
#include "io/mcap_reader.hpp"
#include "tests/io/rosbag2_writer.hpp"

namespace {

/// Seeds: a small bag from the tests' rosbag2 writer, chunked (zstd, lz4, none) and not, with
/// and without the summary.
void write_mcap_seeds() {
  using namespace semap::test;
  const auto dir = semap::fuzz::scratch_dir() / "seeds";
  std::filesystem::create_directories(dir);
  int k = 0;
  for (const auto compression : {McapCompression::zstd, McapCompression::lz4, McapCompression::none})
    for (const bool chunked : {true, false})
      for (const bool summary : {true, false}) {
        const auto file = dir / ("seed" + std::to_string(k++) + ".mcap");
        {
          Rosbag2WriterOptions options{Rosbag2Storage::mcap, compression, chunked, summary, 200, 0};
          Rosbag2Writer bag(file, options);
          for (uint32_t n = 0; n < 2; ++n) {
            bag.write(RosImage{"/c/image", {n, 0}, "rgb8", 2, 2, 6, false, std::vector<uint8_t>(12, 40)});
            bag.write(RosImage{"/d/image", {n, 0}, "16UC1", 2, 2, 4, false, std::vector<uint8_t>(8, 7)});
            bag.write(RosCameraInfo{"/d/camera_info", {n, 0}, 2, 2, {1, 0, 1, 0, 1, 1, 0, 0, 1}, {0, 0, 0, 0, 0}});
          }
        }
        semap::fuzz::write_seed(file.filename().string(), semap::fuzz::read_bytes(file));
      }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  write_mcap_seeds();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = semap::fuzz::input_file("input.mcap", data, size);
  try {
    semap::io_detail::McapReader mcap(path);
    const auto messages = mcap.messages();
    for (size_t i = 0; i < messages.size() && i < 64; ++i) {
      const auto bytes = mcap.read(messages[i]);
      try {
        semap::io_detail::ros2_msgs::image_meta(bytes, i % 2 == 1, path.string());
      } catch (const semap::Error&) {
      }
    }
  } catch (const semap::Error&) {
  }
  return 0;
}
