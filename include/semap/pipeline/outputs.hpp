#pragma once
// Writers over a Mapper's state: what `semap run` leaves in its output folder. Each file is
// written to a temporary name and renamed, so an interrupted write never looks complete.
//
//   trajectory.txt     TUM format, every frame, T_world_camera
//   mesh.ply           binary PLY, vertex x y z red green blue label instance
//   objects.json       + objects/<id>.ply (schema in SHARED_FORMATS.md)
//   map.semap          the TSDF map (versioned, checksummed), with the gravity section
//   map.pgm, map.yaml, map_labels.png, esdf.npy, esdf.yaml, scene_graph.json  (issue 39,
//                      pipeline/navigation_outputs.hpp)
#include <filesystem>
#include <string>
#include <vector>

#include "semap/objects/object_summary.hpp"
#include "semap/mapper.hpp"
#include "semap/pipeline/navigation_outputs.hpp"

namespace semap {

/// The map products read once from a Mapper (the mesh is extracted once for every writer).
struct MapOutputs {
  Trajectory trajectory;
  TriangleMesh mesh;
  std::vector<ObjectSummary> objects;
  NavigationMaps navigation;  ///< gravity frame, occupancy grid, scene graph (issue 39)
};
MapOutputs collect_outputs(const Mapper& mapper);

/// Writes trajectory.txt, mesh.ply, objects.json + objects/*.ply, the navigation maps and
/// scene graph, and map.semap into `dir`
/// (created when missing). Throws semap::Error naming the file that cannot be written.
void write_map_outputs(const Mapper& mapper, const MapOutputs& outputs, const std::filesystem::path& dir);
/// The library's (and Python mapper.save's) whole output: the files above plus report.json,
/// report.html and topdown.png with the keys `semap run` writes (issue 43; the wall/fps/CPU
/// figures that only a driver measures are null there, summary.driver says which wrote it).
void write_map_outputs(const Mapper& mapper, const std::filesystem::path& dir);
/// The files every write_map_outputs(mapper, dir) writes at the top of `dir` (objects/<id>.ply
/// vary with the map and are not listed): `semap run` refuses an output folder holding one
/// that semap did not write before it maps (issue 44), not after.
const std::vector<std::string>& map_output_files();
/// objects.json + objects/<id>.ply.
void write_objects(const std::vector<ObjectSummary>& objects, const std::filesystem::path& dir);

}  // namespace semap
