// TUM trajectory text: parse_tum_trajectory (groundtruth.txt, `semap eval ate` inputs).
#include "semap/core/error.hpp"
#include "fuzz/fuzz_util.hpp"
#include "semap/io/trajectory_io.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  semap::Trajectory t;
  for (int i = 0; i < 3; ++i) {
    semap::Pose p = semap::Pose::Identity();
    p.translation() = Eigen::Vector3d(0.1 * i, -0.2, 1.5);
    t.push_back({1305031102.0 + 0.03 * i, p});
  }
  const auto path = semap::fuzz::scratch_dir() / "seed.txt";
  semap::write_tum_trajectory(path, t);
  semap::fuzz::write_seed("trajectory.txt", "# ground truth\n" + semap::fuzz::read_bytes(path));
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    semap::parse_tum_trajectory(std::string(reinterpret_cast<const char*>(data), size), "fuzz.txt");
  } catch (const semap::Error&) {
  }
  return 0;
}
