#include "semap/pipeline/outputs.hpp"

#include "semap/core/error.hpp"
#include "core/paths.hpp"
#include "pipeline/report.hpp"
#include "semap/io/ply_io.hpp"
#include "semap/io/trajectory_io.hpp"

namespace semap {

MapOutputs collect_outputs(const Mapper& mapper) {
  MapOutputs outputs{mapper.trajectory(), mapper.mesh(), mapper.objects(), {}};
  outputs.navigation = build_navigation_maps(mapper, outputs.mesh, outputs.trajectory, outputs.objects);
  return outputs;
}

void write_objects(const std::vector<ObjectSummary>& objects, const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir / "objects", ec);
  if (ec) throw Error(dir / "objects", "cannot create output folder: " + ec.message());
  for (const ObjectSummary& o : objects) {
    PointCloud cloud;
    cloud.points = o.points;
    cloud.colours = o.colours;
    write_ply(dir / "objects" / (std::to_string(o.id) + ".ply"), cloud);  // atomic
  }
  write_file_atomic(dir / "objects.json", objects_json(objects).dump(2) + "\n");
}

void write_map_outputs(const Mapper& mapper, const MapOutputs& outputs, const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw Error(dir, "cannot create output folder: " + ec.message());
  write_tum_trajectory(dir / "trajectory.txt", outputs.trajectory);
  write_ply(dir / "mesh.ply", outputs.mesh);
  write_objects(outputs.objects, dir);
  write_navigation_maps(outputs.navigation, dir);
  mapper.save(dir / "map.semap", {{kGravitySection, encode_gravity_section(outputs.navigation.gravity)}});
}

const std::vector<std::string>& map_output_files() {
  static const std::vector<std::string> files = {
      "trajectory.txt", "mesh.ply",     "objects.json", "map.pgm",    "map.yaml",    "map_labels.png", "esdf.npy",
      "esdf.yaml",      "scene_graph.json", "map.semap", "report.json", "report.html", "topdown.png"};
  return files;
}

void write_map_outputs(const Mapper& mapper, const std::filesystem::path& dir) {
  const MapOutputs outputs = collect_outputs(mapper);
  write_map_outputs(mapper, outputs, dir);
  write_run_report(dir, library_run_result(mapper, outputs), outputs);  // issue 43: same files as semap run
}

}  // namespace semap
