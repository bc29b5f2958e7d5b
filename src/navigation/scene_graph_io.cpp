// scene_graph.json: writing and reading (schema in README.md "scene_graph.json").
#include <fstream>
#include <sstream>

#include "semap/core/error.hpp"
#include "semap/navigation/scene_graph.hpp"
#include "core/json_text.hpp"

namespace semap {
namespace {

constexpr int kSchemaVersion = 1;

nlohmann::json vec(const Eigen::VectorXd& v) {
  nlohmann::json a = nlohmann::json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back(v[i]);
  return a;
}

/// The N numbers of array `a`, named `what` in errors.
template <int N>
Eigen::Matrix<double, N, 1> read_array(const nlohmann::json& a, const std::string& what, const std::string& source) {
  if (!a.is_array() || a.size() != N) throw Error(source, "'" + what + "' must be an array of " + std::to_string(N) + " numbers");
  Eigen::Matrix<double, N, 1> v;
  for (int i = 0; i < N; ++i) v[i] = a.at(i).get<double>();
  return v;
}

template <int N>
Eigen::Matrix<double, N, 1> read_vec(const nlohmann::json& j, const char* key, const std::string& source) {
  return read_array<N>(j.at(key), key, source);
}

}  // namespace

nlohmann::json to_json(const SceneGraph& g) {
  nlohmann::json j;
  j["schema"] = "semap.scene_graph";
  j["version"] = kSchemaVersion;
  j["frame"] = "gravity";
  nlohmann::json T = nlohmann::json::array();
  const Eigen::Matrix4d m = g.T_W_G.matrix();
  for (int r = 0; r < 4; ++r) T.push_back(vec(m.row(r).transpose()));
  j["T_W_G"] = T;
  j["thresholds"] = {{"on_tolerance_m", g.config.on_tolerance_m},
                     {"floor_support_max_gap_m", g.config.floor_support_max_gap_m},
                     {"near_distance_m", g.config.near_distance_m},
                     {"min_place_area_m2", g.config.min_place_area_m2}};
  nlohmann::json objects = nlohmann::json::array();
  for (const SceneObjectNode& o : g.objects)
    objects.push_back({{"id", object_node_id(o.id)},
                       {"object_id", o.id},
                       {"class", o.class_name},
                       {"confidence", o.confidence},
                       {"centroid_G", vec(o.centroid_G)},
                       {"box_G", {{"center", vec(o.box.center_G)}, {"size_m", vec(o.box.size_m)}, {"yaw_rad", o.box.yaw_rad}}},
                       {"support_height_m", o.support_height_m},
                       {"point_count", o.point_count}});
  j["objects"] = objects;
  nlohmann::json surfaces = nlohmann::json::array();
  for (const SurfaceNode& s : g.surfaces) {
    nlohmann::json node{{"id", s.id}, {"kind", enum_name(kSurfaceKindNames, s.kind)}, {"height_m", s.height_m},
                        {"area_m2", s.area_m2}};
    if (s.kind == SurfaceKind::kWall) {
      node["normal_G"] = vec(s.normal_G);
      node["offset_m"] = s.offset_m;
      node["segment_G"] = {vec(s.segment_G[0]), vec(s.segment_G[1])};
      node["bottom_m"] = s.bottom_m;
    }
    node["evidence"] = s.evidence;
    surfaces.push_back(std::move(node));
  }
  j["surfaces"] = surfaces;
  nlohmann::json places = nlohmann::json::array();
  for (const PlaceNode& p : g.places)
    places.push_back({{"id", p.id},
                      {"area_m2", p.area_m2},
                      {"centroid_G", vec(p.centroid_G)},
                      {"cells", p.cells},
                      {"evidence", p.evidence}});
  j["places"] = places;
  nlohmann::json edges = nlohmann::json::array();
  for (const SceneEdge& e : g.edges)
    edges.push_back({{"relation", enum_name(kRelationNames, e.relation)}, {"source", e.source}, {"target", e.target},
                     {"evidence", e.evidence}});
  j["edges"] = edges;
  return j;
}

SceneGraph scene_graph_from_json(const nlohmann::json& j, const std::string& source) {
  try {
    if (!j.is_object() || j.value("schema", "") != "semap.scene_graph")
      throw Error(source, "not a semap scene graph (schema is not semap.scene_graph)");
    if (j.at("version").get<int>() > kSchemaVersion)
      throw Error(source, "scene graph version " + std::to_string(j.at("version").get<int>()) + " is newer than this semap reads");
    SceneGraph g;
    const nlohmann::json& T = j.at("T_W_G");
    if (!T.is_array() || T.size() != 4) throw Error(source, "'T_W_G' must be a 4x4 array");
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) g.T_W_G.matrix()(r, c) = T.at(r).at(c).get<double>();
    const nlohmann::json& th = j.at("thresholds");
    g.config.on_tolerance_m = th.at("on_tolerance_m").get<double>();
    g.config.near_distance_m = th.at("near_distance_m").get<double>();
    g.config.floor_support_max_gap_m = th.value("floor_support_max_gap_m", g.config.floor_support_max_gap_m);
    g.config.min_place_area_m2 = th.at("min_place_area_m2").get<double>();
    for (const nlohmann::json& o : j.at("objects")) {
      SceneObjectNode n;
      n.id = o.at("object_id").get<uint32_t>();
      n.class_name = o.at("class").get<std::string>();
      n.confidence = o.at("confidence").get<double>();
      n.centroid_G = read_vec<3>(o, "centroid_G", source);
      const nlohmann::json& b = o.at("box_G");
      n.box.center_G = read_vec<3>(b, "center", source);
      n.box.size_m = read_vec<3>(b, "size_m", source);
      n.box.yaw_rad = b.at("yaw_rad").get<double>();
      n.support_height_m = o.value("support_height_m", n.box.top_m());  // files before it: the box top
      n.point_count = o.at("point_count").get<size_t>();
      g.objects.push_back(std::move(n));
    }
    for (const nlohmann::json& s : j.at("surfaces")) {
      SurfaceNode n;
      n.id = s.at("id").get<std::string>();
      const auto kind = enum_value(kSurfaceKindNames, s.at("kind").get<std::string>());
      if (!kind) throw Error(source, "unknown surface kind '" + s.at("kind").get<std::string>() + "'");
      n.kind = *kind;
      n.height_m = s.at("height_m").get<double>();
      n.area_m2 = s.at("area_m2").get<double>();
      if (n.kind == SurfaceKind::kWall && s.contains("normal_G")) {  // version 1 files before walls have none
        n.normal_G = read_vec<2>(s, "normal_G", source);
        n.offset_m = s.at("offset_m").get<double>();
        const nlohmann::json& seg = s.at("segment_G");
        if (!seg.is_array() || seg.size() != 2) throw Error(source, "'segment_G' must hold two points");
        n.segment_G = {read_array<2>(seg[0], "segment_G[0]", source), read_array<2>(seg[1], "segment_G[1]", source)};
        n.bottom_m = s.at("bottom_m").get<double>();
      }
      n.evidence = s.value("evidence", nlohmann::json::object());
      g.surfaces.push_back(n);
    }
    for (const nlohmann::json& p : j.at("places"))
      g.places.push_back({p.at("id").get<std::string>(), p.at("area_m2").get<double>(), read_vec<2>(p, "centroid_G", source),
                          p.at("cells").get<size_t>(), p.value("evidence", nlohmann::json::object())});
    for (const nlohmann::json& e : j.at("edges")) {
      const auto relation = enum_value(kRelationNames, e.at("relation").get<std::string>());
      if (!relation) throw Error(source, "unknown relation '" + e.at("relation").get<std::string>() + "'");
      g.edges.push_back({*relation, e.at("source").get<std::string>(), e.at("target").get<std::string>(), e.at("evidence")});
    }
    return g;
  } catch (const nlohmann::json::exception& e) {
    throw Error(source, "malformed scene graph: " + json_error_text(e));
  }
}

SceneGraph load_scene_graph(const std::filesystem::path& folder_or_file) {
  std::error_code ec;
  const std::filesystem::path path =
      std::filesystem::is_directory(folder_or_file, ec) ? folder_or_file / "scene_graph.json" : folder_or_file;
  std::ifstream in(path);
  if (!in) throw Error(path, "cannot open the scene graph");
  std::stringstream text;
  text << in.rdbuf();
  nlohmann::json j = nlohmann::json::parse(text.str(), nullptr, false);
  if (j.is_discarded()) throw Error(path, "not valid JSON");
  return scene_graph_from_json(j, path.string());
}

}  // namespace semap
