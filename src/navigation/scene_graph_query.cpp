// `semap query`: objects of a scene graph by class and relation (scene_graph.hpp SceneQuery).
#include <algorithm>
#include <map>
#include <unordered_map>

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

/// The matches of one object, capped at kMaxQueryMatchesPerObject (total counts all).
struct Matches {
  nlohmann::json list = nlohmann::json::array();
  size_t total = 0;
  void add(nlohmann::json match) {
    if (list.size() < kMaxQueryMatchesPerObject) list.push_back(std::move(match));
    ++total;
  }
};

}  // namespace

void query_scene_graph(const SceneGraph& graph, const SceneQuery& query,
                       const std::function<void(const nlohmann::json&)>& emit) {
  std::map<std::string, const SceneObjectNode*> objects;
  for (const SceneObjectNode& o : graph.objects) objects[object_node_id(o.id)] = &o;
  std::unordered_map<std::string, std::vector<const SceneEdge*>> edges_from;  // one pass over the edges
  for (const SceneEdge& e : graph.edges) edges_from[e.source].push_back(&e);
  const double within = query.within_m >= 0 ? query.within_m : graph.config.near_distance_m;
  const nlohmann::json all_nodes = to_json(graph)["objects"];
  std::vector<std::pair<double, const SceneObjectNode*>> near;
  for (size_t i = 0; i < graph.objects.size(); ++i) {
    const SceneObjectNode& o = graph.objects[i];
    if (!query.class_name.empty() && o.class_name != query.class_name) continue;
    const std::string id = object_node_id(o.id);
    Matches matches;
    auto relation_holds = [&](Relation r, const std::string& target) {
      if (target.empty()) return true;
      bool found = false;
      const auto it = edges_from.find(id);
      if (it != edges_from.end())
        for (const SceneEdge* e : it->second)
          if (e->relation == r && node_matches(objects, e->target, target)) {
            matches.add({{"relation", enum_name(kRelationNames, r)}, {"target", e->target}, {"evidence", e->evidence}});
            found = true;
          }
      return found;
    };
    if (!relation_holds(Relation::kOn, query.on) || !relation_holds(Relation::kIn, query.in)) continue;
    if (!query.near.empty()) {
      near.clear();
      for (const SceneObjectNode& other : graph.objects) {
        if (other.id == o.id || other.class_name != query.near) continue;
        const double d = (other.centroid_G - o.centroid_G).norm();
        if (d <= within) near.emplace_back(d, &other);
      }
      if (near.empty()) continue;
      const size_t shown = std::min(near.size(), kMaxQueryMatchesPerObject);
      std::partial_sort(near.begin(), near.begin() + static_cast<std::ptrdiff_t>(shown), near.end(),
                        [](const auto& a, const auto& b) { return a.first < b.first; });
      for (size_t k = 0; k < shown; ++k)
        matches.add({{"relation", "near"}, {"target", object_node_id(near[k].second->id)},
                     {"evidence", {{"distance_m", near[k].first}, {"threshold_m", within}}}});
      matches.total += near.size() - shown;
    }
    nlohmann::json node = all_nodes[i];
    node["matches"] = std::move(matches.list);
    node["matches_total"] = matches.total;
    emit(node);
  }
}

std::vector<nlohmann::json> query_scene_graph(const SceneGraph& graph, const SceneQuery& query) {
  std::vector<nlohmann::json> out;
  query_scene_graph(graph, query, [&](const nlohmann::json& node) { out.push_back(node); });
  return out;
}

}  // namespace semap
