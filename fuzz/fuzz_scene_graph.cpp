// scene_graph.json (issue 39, written by `semap run`, read by `semap query` and
// semap.load_scene_graph): load_scene_graph then query_scene_graph on what it accepted.
#include "semap/core/error.hpp"
#include "fuzz/fuzz_util.hpp"
#include "semap/navigation/scene_graph.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  semap::SceneGraph graph;
  for (uint32_t id : {1u, 2u}) {
    semap::SceneObjectNode node;
    node.id = id;
    node.class_name = id == 1 ? "table" : "cup";
    node.confidence = 0.8;
    node.centroid_G = {1.0, 2.0, id == 1 ? 0.4 : 0.8};
    node.box.center_G = node.centroid_G;
    node.box.size_m = id == 1 ? Eigen::Vector3d(1.2, 0.8, 0.75) : Eigen::Vector3d(0.08, 0.08, 0.1);
    node.point_count = 100;
    graph.objects.push_back(node);
  }
  graph.surfaces.push_back({"floor", semap::SurfaceKind::kFloor, 0.0, 12.5});
  graph.places.push_back({"place_0", 10.0, Eigen::Vector2d(1.0, 1.0), 4000});
  graph.edges.push_back({semap::Relation::kOn, semap::object_node_id(2), semap::object_node_id(1), {{"gap_m", 0.01}}});
  graph.edges.push_back({semap::Relation::kOn, semap::object_node_id(1), "floor", {{"gap_m", 0.0}}});
  graph.edges.push_back({semap::Relation::kInPlace, semap::object_node_id(1), "place_0", nlohmann::json::object()});
  semap::fuzz::write_seed("scene_graph.json", semap::to_json(graph).dump(2));
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = semap::fuzz::input_file("scene_graph.json", data, size);
  try {
    const semap::SceneGraph graph = semap::load_scene_graph(path);
    semap::SceneQuery query;
    query.class_name = "cup";
    query.on = "table";
    query.near = "table";
    semap::query_scene_graph(graph, query);
  } catch (const semap::Error&) {
  }
  return 0;
}
