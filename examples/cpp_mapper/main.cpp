// cpp_mapper DATASET OUT_DIR: maps a dataset with semap::Mapper in the application's own
// loop and writes OUT_DIR/trajectory.txt (TUM format) and OUT_DIR/mesh.ply.
#include <semap/semap.hpp>

#include <cstdio>
#include <filesystem>

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: cpp_mapper DATASET OUT_DIR\n");
    return 2;
  }
  try {
    // Any layout semap reads (TUM, 7-Scenes, ScanNet, ROS bag, ...): frames decode lazily.
    const auto dataset = semap::open_dataset(argv[1]);
    semap::SemapConfig config;          // the defaults of `semap config --dump`
    config.pipeline.threads = 1;        // one thread: the same result on every run
    semap::Mapper mapper(config, dataset->camera());

    for (size_t i = 0; i < dataset->size(); ++i) {
      const semap::FrameResult r = mapper.add_frame(dataset->load(i));
      if (r.status == semap::FrameStatus::lost) std::fprintf(stderr, "frame %zu: tracking lost\n", i);
    }
    mapper.finish();  // final pose graph, map refresh with the optimised poses

    const std::filesystem::path out = argv[2];
    std::filesystem::create_directories(out);
    const semap::TriangleMesh mesh = mapper.mesh();  // extracted now, with RGB, class and object ids
    semap::write_tum_trajectory(out / "trajectory.txt", mapper.trajectory());
    semap::write_ply(out / "mesh.ply", mesh);
    const semap::MapperStats stats = mapper.stats();
    std::printf("%zu frames, %zu keyframes, %zu loop edges, %zu mesh vertices -> %s\n", stats.frames,
                stats.keyframes, stats.loop_edges, mesh.vertices.size(), out.c_str());
    return 0;
  } catch (const semap::Error& e) {
    std::fprintf(stderr, "cpp_mapper: %s\n", e.what());
    return 1;
  }
}
