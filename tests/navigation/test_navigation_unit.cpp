// Issue 39 units on hand-made inputs: the grid from a TSDF holding a floor and a box, the file
// formats (map_server PGM/YAML, .npy), the 3D distance queries and the `on` rule.
#include <gtest/gtest.h>

#include <cmath>

#include "semap/navigation/distance_query.hpp"
#include "semap/navigation/map_files.hpp"
#include "semap/navigation/scene_graph.hpp"

using namespace semap;

namespace {

/// A TSDF with the true signed distance (truncated) to a floor plane z = 0 and an axis-aligned
/// box [0.4, 0.8] x [0.4, 0.8] x [0, 0.5], observed in [0, 1.2]^2 x [-0.1, 0.7].
TsdfMap floor_and_box_map() {
  TsdfConfig config;
  config.voxel_size = 0.02;
  TsdfMap map(config);
  const float trunc = static_cast<float>(config.truncation_voxels * config.voxel_size);
  for (int z = -5; z < 35; ++z)
    for (int y = 0; y < 60; ++y)
      for (int x = 0; x < 60; ++x) {
        const VoxelIndex v(x, y, z);
        const Eigen::Vector3f p = map.voxel_centre(v);
        const Eigen::Vector3f lo(0.4f, 0.4f, 0.f), hi(0.8f, 0.8f, 0.5f);
        const Eigen::Vector3f outside = (lo - p).cwiseMax(p - hi).cwiseMax(0.f);
        float box = outside.norm();
        if (box == 0.f) box = std::max((lo - p).cwiseMax(p - hi).maxCoeff(), -trunc);
        const float sdf = std::clamp(std::min(p.z(), box), -trunc, trunc);
        Block& b = map.allocate_block(block_of_voxel(v));
        TsdfVoxel& voxel = b.voxels[local_index(v)];
        voxel.set_sdf(sdf);
        voxel.weight_q = 10;
      }
  return map;
}

}  // namespace

TEST(NavigationUnit, GridMarksBoxOccupiedAndFloorFree) {
  const TsdfMap map = floor_and_box_map();
  NavigationConfig config;
  const OccupancyGrid grid = build_occupancy_grid(map, Pose::Identity(), config);
  ASSERT_GT(grid.width, 20);
  auto state = [&](double x, double y) { return grid.state_at_W({x, y, 0.3}); };
  EXPECT_EQ(state(0.6, 0.6), CellState::kOccupied);   // under the box top
  EXPECT_EQ(state(0.41, 0.6), CellState::kOccupied);  // its side
  EXPECT_EQ(state(0.2, 0.2), CellState::kFree);
  EXPECT_EQ(state(1.0, 1.1), CellState::kFree);
  EXPECT_EQ(state(3.0, 3.0), CellState::kUnknown);
  // Every cell's state against the geometry, away from the box's edges.
  size_t decided = 0, agree = 0;
  for (int iy = 0; iy < grid.height; ++iy)
    for (int ix = 0; ix < grid.width; ++ix) {
      const Eigen::Vector2d c = grid.cell_centre(ix, iy);
      const double edge = std::min({std::abs(c.x() - 0.4), std::abs(c.x() - 0.8), std::abs(c.y() - 0.4), std::abs(c.y() - 0.8)});
      if (edge < 0.05 || c.x() < 0.05 || c.y() < 0.05 || c.x() > 1.15 || c.y() > 1.15) continue;
      const bool in_box = c.x() > 0.4 && c.x() < 0.8 && c.y() > 0.4 && c.y() < 0.8;
      ++decided;
      agree += grid.state[grid.index(ix, iy)] == (in_box ? CellState::kOccupied : CellState::kFree);
    }
  EXPECT_GT(decided, 300u);
  EXPECT_EQ(agree, decided);
  // The distance field: 0 in the box, about the distance to its side outside.
  const std::vector<float> d = distance_to_obstacles_m(grid);
  const Eigen::Vector2i c = grid.cell_of({0.2, 0.6});
  EXPECT_NEAR(d[grid.index(c.x(), c.y())], 0.2, 0.05);
}

TEST(NavigationUnit, FilesFollowMapServerAndNpyFormats) {
  OccupancyGrid grid;
  grid.width = 3, grid.height = 2, grid.resolution_m = 0.1;
  grid.origin_G = {-1.0, 2.0};
  grid.state = {CellState::kOccupied, CellState::kFree, CellState::kUnknown,
                CellState::kFree, CellState::kFree, CellState::kFree};
  grid.top_label.assign(6, 0);
  grid.top_height_m.assign(6, 0.f);
  const std::string pgm = map_pgm(grid);
  const std::string header = "P5\n3 2\n255\n";
  ASSERT_EQ(pgm.substr(0, header.size()), header);
  // The first image row is the grid's top row (iy = 1): all free; then occupied, free, unknown.
  EXPECT_EQ(pgm.substr(header.size()), std::string("\xfe\xfe\xfe\x00\xfe\xcd", 6));
  const std::string yaml = map_yaml(grid, "map.pgm");
  EXPECT_NE(yaml.find("origin: [-1, 2, 0.0]"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("resolution: 0.1\n"), std::string::npos);
  EXPECT_NE(yaml.find("negate: 0\n"), std::string::npos);
  const std::string npy = npy_float32({1.f, 2.f, 3.f, 4.f, 5.f, 6.f}, 2, 3);
  EXPECT_EQ(npy.substr(0, 6), "\x93NUMPY");
  const size_t header_len = static_cast<uint8_t>(npy[8]) | (static_cast<uint8_t>(npy[9]) << 8);
  EXPECT_EQ((10 + header_len) % 64, 0u);
  EXPECT_NE(npy.find("'shape': (2, 3)"), std::string::npos);
  EXPECT_EQ(npy.size(), 10 + header_len + 6 * sizeof(float));
}

TEST(NavigationUnit, DistanceQueriesFollowTheSurface) {
  const TsdfMap map = floor_and_box_map();
  const DistanceQuery query(map);
  EXPECT_NEAR(query.distance_m({0.2, 0.2, 0.05}), 0.05, 0.01);  // above the floor
  EXPECT_NEAR(query.distance_m({0.6, 0.6, 0.55}), 0.05, 0.01);  // above the box
  EXPECT_LT(query.distance_m({0.6, 0.6, 0.47}), 0.0);           // inside it
  EXPECT_TRUE(std::isnan(query.distance_m({5.0, 5.0, 5.0})));   // never observed
  EXPECT_TRUE(query.is_free({0.2, 0.2, 0.3}, 0.1));
  EXPECT_FALSE(query.is_free({0.2, 0.2, 0.3}, 0.35));  // reaches the floor
  EXPECT_FALSE(query.is_free({0.3, 0.6, 0.3}, 0.15));  // reaches the box side
  EXPECT_FALSE(query.is_free({5.0, 5.0, 5.0}, 0.1));   // unknown
}

TEST(NavigationUnit, OnEdgesPickTheSupportRightUnder) {
  auto object = [](uint32_t id, ClassId cls, Eigen::Vector3f lo, Eigen::Vector3f hi) {
    ObjectSummary o;
    o.id = id;
    o.class_id = cls;
    for (float x = lo.x(); x <= hi.x(); x += 0.02f)
      for (float y = lo.y(); y <= hi.y(); y += 0.02f)
        for (float z = lo.z(); z <= hi.z(); z += 0.02f) o.points.emplace_back(x, y, z);
    o.centroid = 0.5f * (lo + hi);
    return o;
  };
  const ClassId table = *class_from_name("table"), cup = *class_from_name("cup");
  const std::vector<ObjectSummary> objects = {object(1, table, {0, 0, 0}, {1.0f, 0.6f, 0.74f}),
                                              object(2, cup, {0.3f, 0.2f, 0.76f}, {0.38f, 0.28f, 0.86f}),
                                              object(3, cup, {2.0f, 2.0f, 0.76f}, {2.08f, 2.08f, 0.86f})};
  OccupancyGrid grid;  // an empty grid: no floor mapped
  NavigationConfig config;
  const SceneGraph g = build_scene_graph(objects, grid, {}, config);
  std::vector<std::pair<std::string, std::string>> on;
  for (const SceneEdge& e : g.edges)
    if (e.relation == Relation::kOn) on.emplace_back(e.source, e.target);
  // The cup over the table rests on it; the one beside it at table height rests on nothing.
  EXPECT_EQ(on, (std::vector<std::pair<std::string, std::string>>{{"object_2", "object_1"}}));
  // The cup rests on the table, it is not in it (its box lies within the table's grown box).
  for (const SceneEdge& e : g.edges) EXPECT_NE(e.relation, Relation::kIn) << e.source << " in " << e.target;
  const SceneGraph again = scene_graph_from_json(to_json(g), "test");
  EXPECT_EQ(to_json(again), to_json(g));
}

// Real tables carry clutter the object map counts as table: the box reaches above the top the
// cups stand on. The support height is the top surface (densest layer), and a cup resting on
// the table is `on` it, not `in` it; a chair pushed under the table sticks out: not `in` either.
TEST(NavigationUnit, ClutteredTableCarriesItsCupAndHoldsNothing) {
  const ClassId table = *class_from_name("table"), cup = *class_from_name("cup"), chair = *class_from_name("chair");
  ObjectSummary t;
  t.id = 1, t.class_id = table;
  for (float x = 0; x <= 1.2f; x += 0.02f)
    for (float y = 0; y <= 0.8f; y += 0.02f) t.points.emplace_back(x, y, 0.74f);  // the top
  for (float z = 0; z < 0.74f; z += 0.02f)
    for (const Eigen::Vector2f leg : {Eigen::Vector2f(0.05f, 0.05f), Eigen::Vector2f(1.15f, 0.75f)})
      t.points.emplace_back(leg.x(), leg.y(), z);
  for (float x = 0.6f; x <= 0.9f; x += 0.02f)  // a pile of papers the map gave the table, 15 cm high
    for (float z = 0.76f; z <= 0.9f; z += 0.02f) t.points.emplace_back(x, 0.6f, z);
  t.centroid = Eigen::Vector3f(0.6f, 0.4f, 0.7f);
  auto block = [](uint32_t id, ClassId c, Eigen::Vector3f lo, Eigen::Vector3f hi) {
    ObjectSummary o;
    o.id = id, o.class_id = c, o.centroid = 0.5f * (lo + hi);
    for (float x = lo.x(); x <= hi.x(); x += 0.02f)
      for (float y = lo.y(); y <= hi.y(); y += 0.02f)
        for (float z = lo.z(); z <= hi.z(); z += 0.02f) o.points.emplace_back(x, y, z);
    return o;
  };
  const std::vector<ObjectSummary> objects = {t, block(2, cup, {0.3f, 0.2f, 0.75f}, {0.38f, 0.28f, 0.84f}),
                                              block(3, chair, {0.4f, 0.5f, 0.0f}, {0.8f, 0.9f, 0.95f})};
  const SceneGraph g = build_scene_graph(objects, OccupancyGrid{}, {}, NavigationConfig{});
  ASSERT_EQ(g.objects.size(), 3u);
  EXPECT_GT(g.objects[0].box.top_m(), 0.8) << "the clutter lifts the box";
  EXPECT_NEAR(g.objects[0].support_height_m, 0.74, 0.01);
  size_t on = 0;
  for (const SceneEdge& e : g.edges) {
    EXPECT_NE(e.relation, Relation::kIn) << e.source << " in " << e.target;
    on += e.relation == Relation::kOn && e.source == "object_2" && e.target == "object_1";
  }
  EXPECT_EQ(on, 1u);
}

namespace semap {
namespace {

TEST(NavigationUnit, QueriesListTheNearestMatchesAndCountTheRest) {
  // 300 chairs on a 10 cm grid around a cup on a table: every chair is near the cup.
  SceneGraph graph;
  graph.config.near_distance_m = 10.0;
  SceneObjectNode table{.id = 1, .class_name = "table"}, cup{.id = 2, .class_name = "cup"};
  cup.centroid_G = {0.0, 0.0, 0.8};
  graph.objects = {table, cup};
  for (uint32_t k = 0; k < 300; ++k) {
    SceneObjectNode chair{.id = 10 + k, .class_name = "chair"};
    chair.centroid_G = {0.1 * (1 + k % 20), 0.1 * (k / 20), 0.8};
    graph.objects.push_back(chair);
  }
  graph.edges.push_back({Relation::kOn, "object_2", "object_1", {{"gap_m", 0.0}}});
  const std::vector<nlohmann::json> near = query_scene_graph(graph, {.class_name = "cup", .near = "chair"});
  ASSERT_EQ(near.size(), 1u);
  const nlohmann::json& matches = near[0]["matches"];
  ASSERT_EQ(matches.size(), kMaxQueryMatchesPerObject);
  EXPECT_EQ(near[0]["matches_total"].get<size_t>(), 300u);
  EXPECT_EQ(matches[0]["target"], "object_10");  // 10 cm away: the nearest first
  for (size_t k = 1; k < matches.size(); ++k)
    EXPECT_LE(matches[k - 1]["evidence"]["distance_m"].get<double>(), matches[k]["evidence"]["distance_m"].get<double>());
  // Relations by edge: the cup is on the table; no chair is on anything.
  const auto on = query_scene_graph(graph, {.on = "table"});
  ASSERT_EQ(on.size(), 1u);
  EXPECT_EQ(on[0]["id"], "object_2");
  EXPECT_EQ(on[0]["matches_total"].get<size_t>(), 1u);
  EXPECT_TRUE(query_scene_graph(graph, {.class_name = "chair", .on = "table"}).empty());
}

}  // namespace
}  // namespace semap
