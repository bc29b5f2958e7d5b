// rosbag2 folders (issue 40): metadata.yaml and a SQLite3 .db3 through open_dataset (topic
// detection, CameraInfo, association, decoding of frame 0). The input is metadata.yaml, a NUL
// byte, then the bytes of the one storage file it may list (bag_0.db3).
#include <cstring>

#include "semap/core/error.hpp"
#include "semap/io/dataset.hpp"
#include "fuzz/fuzz_util.hpp"
#include "tests/io/rosbag2_writer.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  using namespace semap::test;
  for (const auto storage : {Rosbag2Storage::sqlite_humble, Rosbag2Storage::sqlite_jazzy}) {
    const auto folder = semap::fuzz::scratch_dir() / "seed_bag";
    std::filesystem::remove_all(folder);
    {
      Rosbag2Writer bag(folder, {storage});
      for (uint32_t n = 0; n < 2; ++n) {
        bag.write(RosImage{"/c/image", {n, 0}, "rgb8", 2, 2, 6, false, std::vector<uint8_t>(12, 40)});
        bag.write(RosImage{"/d/image", {n, 0}, "16UC1", 2, 2, 4, false, std::vector<uint8_t>(8, 7)});
        bag.write(RosCameraInfo{"/d/camera_info", {n, 0}, 2, 2, {1, 0, 1, 0, 1, 1, 0, 0, 1}, {0, 0, 0, 0, 0}});
      }
    }
    std::string yaml = semap::fuzz::read_bytes(folder / "metadata.yaml");
    const std::string needle = "seed_bag_0.db3";
    yaml.replace(yaml.find(needle), needle.size(), "bag_0.db3");
    semap::fuzz::write_seed(storage == Rosbag2Storage::sqlite_humble ? "humble" : "jazzy",
                            yaml + std::string(1, '\0') + semap::fuzz::read_bytes(folder / "seed_bag_0.db3"));
    std::filesystem::remove_all(folder);
  }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto folder = semap::fuzz::scratch_dir() / "bag";
  std::filesystem::create_directories(folder);
  const auto* nul = static_cast<const uint8_t*>(std::memchr(data, 0, size));
  const size_t yaml_size = nul ? static_cast<size_t>(nul - data) : size;
  semap::fuzz::write_bytes(folder / "metadata.yaml", data, yaml_size);
  const size_t rest = nul ? size - yaml_size - 1 : 0;
  semap::fuzz::write_bytes(folder / "bag_0.db3", nul ? nul + 1 : data, rest);
  try {
    semap::open_dataset(folder)->load(0);
  } catch (const semap::Error&) {
  }
  return 0;
}
