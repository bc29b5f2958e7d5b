// PLY reader (binary little endian and ASCII): parse_ply.
#include "semap/core/error.hpp"
#include "fuzz/fuzz_util.hpp"
#include "semap/io/ply_io.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  semap::TriangleMesh mesh;
  mesh.vertices.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.vertices.colours = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}};
  mesh.vertices.labels = {1, 2, 3};
  mesh.vertices.instances = {0, 7, 7};
  mesh.triangles = {{0, 1, 2}};
  const auto path = semap::fuzz::scratch_dir() / "seed.ply";
  semap::write_ply(path, mesh);
  semap::fuzz::write_seed("mesh_binary.ply", semap::fuzz::read_bytes(path));
  semap::fuzz::write_seed("cloud_ascii.ply",
                          "ply\nformat ascii 1.0\ncomment x\nelement vertex 2\nproperty float x\nproperty float y\n"
                          "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
                          "property int extra\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                          "0 0 0 1 2 3 7\n1 1 1 4 5 6 8\n3 0 1 1\n");
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    semap::parse_ply(std::string(reinterpret_cast<const char*>(data), size), "fuzz.ply");
  } catch (const semap::Error&) {
  }
  return 0;
}
