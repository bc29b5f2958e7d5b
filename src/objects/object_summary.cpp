#include "semap/objects/object_summary.hpp"

namespace semap {

nlohmann::json to_json(const ObjectSummary& o) {
  auto vec = [](const Eigen::Vector3f& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); };
  std::vector<float> rotation;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) rotation.push_back(o.box.rotation(r, c));
  return {{"id", o.id},
          {"class", std::string(class_name(o.class_id))},
          {"class_id", o.class_id},
          {"class_distribution", o.class_distribution},
          {"confidence", o.confidence},
          {"n", o.merge_count},
          {"association_count", o.associations},
          {"centroid", vec(o.centroid)},
          {"aabb", {{"min", vec(o.aabb_min)}, {"max", vec(o.aabb_max)}}},
          {"obb", {{"center", vec(o.box.center)}, {"extent", vec(o.box.extent)}, {"rotation", rotation}}},
          {"point_count", o.points.size()},
          {"points_file", "objects/" + std::to_string(o.id) + ".ply"},
          {"first_seen", o.first_frame},
          {"last_seen", o.last_frame},
          {"state", o.state}};
}

nlohmann::json objects_json(const std::vector<ObjectSummary>& objects) {
  nlohmann::json list = nlohmann::json::array();
  for (const auto& o : objects) list.push_back(to_json(o));
  return {{"objects", list}};
}

}  // namespace semap
