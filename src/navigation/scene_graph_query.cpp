// `semap query`: objects of a scene graph by class and relation (scene_graph.hpp SceneQuery).
#include <map>

#include "semap/navigation/scene_graph.hpp"

namespace semap {
namespace {

/// Whether node `id` is what `name` asks for: its id, or an object of that class, or the floor.
bool node_matches(const std::map<std::string, const SceneObjectNode*>& objects, const std::string& id,
                  const std::string& name) {
  if (id == name) return true;
  const auto it = objects.find(id);
  return it != objects.end() && it->second->class_name == name;
}

}  // namespace

std::vector<nlohmann::json> query_scene_graph(const SceneGraph& graph, const SceneQuery& query) {
  std::map<std::string, const SceneObjectNode*> objects;
  for (const SceneObjectNode& o : graph.objects) objects[object_node_id(o.id)] = &o;
  const double within = query.within_m >= 0 ? query.within_m : graph.config.near_distance_m;
  const nlohmann::json all_nodes = to_json(graph)["objects"];
  std::vector<nlohmann::json> out;
  for (size_t i = 0; i < graph.objects.size(); ++i) {
    const SceneObjectNode& o = graph.objects[i];
    if (!query.class_name.empty() && o.class_name != query.class_name) continue;
    const std::string id = object_node_id(o.id);
    nlohmann::json matches = nlohmann::json::array();
    auto relation_holds = [&](Relation r, const std::string& target) {
      if (target.empty()) return true;
      bool found = false;
      for (const SceneEdge& e : graph.edges)
        if (e.relation == r && e.source == id && node_matches(objects, e.target, target)) {
          matches.push_back({{"relation", enum_name(kRelationNames, r)}, {"target", e.target}, {"evidence", e.evidence}});
          found = true;
        }
      return found;
    };
    if (!relation_holds(Relation::kOn, query.on) || !relation_holds(Relation::kIn, query.in)) continue;
    if (!query.near.empty()) {
      bool found = false;
      for (const SceneObjectNode& other : graph.objects) {
        if (other.id == o.id || other.class_name != query.near) continue;
        const double d = (other.centroid_G - o.centroid_G).norm();
        if (d > within) continue;
        matches.push_back({{"relation", "near"}, {"target", object_node_id(other.id)},
                           {"evidence", {{"distance_m", d}, {"threshold_m", within}}}});
        found = true;
      }
      if (!found) continue;
    }
    nlohmann::json node = all_nodes[i];
    node["matches"] = matches;
    out.push_back(std::move(node));
  }
  return out;
}

}  // namespace semap
