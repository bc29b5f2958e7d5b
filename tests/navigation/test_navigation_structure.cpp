// Issue 39 structural nodes and places on hand-made inputs with known answers: the walls and
// ceiling of a tilted, noisy room mesh with furniture in it (navigation/structure.hpp), and the
// places of a two-room grid joined by a door (navigation/places.hpp), with in_place edges.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <set>
#include <random>

#include "semap/navigation/places.hpp"
#include "semap/navigation/scene_graph.hpp"
#include "semap/navigation/structure.hpp"

using namespace semap;

namespace {

/// Appends the rectangle corner + [0, 1] u + [0, 1] v as triangles of about `step_m`, wound so
/// that their normal points along `facing`, with class `label`; vertices jittered by up to
/// `jitter_m` and mapped into the world by T_W_G.
void add_rectangle(TriangleMesh& mesh, const Eigen::Vector3d& corner, Eigen::Vector3d u, Eigen::Vector3d v,
                   const Eigen::Vector3d& facing, ClassId label, const Pose& T_W_G, std::mt19937& rng,
                   double jitter_m = 0.01, double step_m = 0.1) {
  if (u.cross(v).dot(facing) < 0) std::swap(u, v);
  const int nu = std::max(1, static_cast<int>(std::round(u.norm() / step_m)));
  const int nv = std::max(1, static_cast<int>(std::round(v.norm() / step_m)));
  std::uniform_real_distribution<double> noise(-jitter_m, jitter_m);
  const uint32_t base = static_cast<uint32_t>(mesh.vertices.points.size());
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i <= nu; ++i) {
      const Eigen::Vector3d p = corner + u * i / nu + v * j / nv + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
      mesh.vertices.points.push_back((T_W_G * p).cast<float>());
      mesh.vertices.labels.push_back(label);
    }
  const auto at = [&](int i, int j) { return base + static_cast<uint32_t>(j * (nu + 1) + i); };
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      mesh.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      mesh.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
}

/// A closed box's four sides and top (outward), for furniture.
void add_box(TriangleMesh& mesh, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, ClassId label, const Pose& T,
             std::mt19937& rng) {
  const Eigen::Vector3d s = hi - lo;
  const Eigen::Vector3d X = Eigen::Vector3d::UnitX(), Y = Eigen::Vector3d::UnitY(), Z = Eigen::Vector3d::UnitZ();
  add_rectangle(mesh, lo, s.y() * Y, s.z() * Z, -X, label, T, rng, 0.005);
  add_rectangle(mesh, lo + s.x() * X, s.y() * Y, s.z() * Z, X, label, T, rng, 0.005);
  add_rectangle(mesh, lo, s.x() * X, s.z() * Z, -Y, label, T, rng, 0.005);
  add_rectangle(mesh, lo + s.y() * Y, s.x() * X, s.z() * Z, Y, label, T, rng, 0.005);
  add_rectangle(mesh, lo + s.z() * Z, s.x() * X, s.y() * Y, Z, label, T, rng, 0.005);
}

ClassId cls(const char* name) { return *class_from_name(name); }

}  // namespace

// A 4 x 3 x 2.5 m room, walls facing in, in a world rotated like a camera frame (y down): its
// four walls and its ceiling are found where they are; a table and a low unlabelled counter
// (vertical sides under wall_min_top_m) are no walls.
TEST(NavigationStructure, RoomMeshGivesFourWallsAndTheCeiling) {
  Pose T_W_G = Pose::Identity();
  T_W_G.linear() = Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix() *
                   Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T_W_G.translation() = Eigen::Vector3d(0.5, 1.2, 2.0);
  std::mt19937 rng(7);
  TriangleMesh mesh;
  const Eigen::Vector3d X = Eigen::Vector3d::UnitX(), Y = Eigen::Vector3d::UnitY(), Z = Eigen::Vector3d::UnitZ();
  const double W = 4.0, D = 3.0, H = 2.5;
  add_rectangle(mesh, {0, 0, 0}, W * X, D * Y, Z, cls("floor"), T_W_G, rng);
  add_rectangle(mesh, {0, 0, H}, W * X, D * Y, -Z, cls("ceiling"), T_W_G, rng);
  add_rectangle(mesh, {0, 0, 0}, D * Y, H * Z, X, cls("wall"), T_W_G, rng);       // x = 0, faces +x
  add_rectangle(mesh, {W, 0, 0}, D * Y, H * Z, -X, cls("wall"), T_W_G, rng);      // x = 4, faces -x
  add_rectangle(mesh, {0, 0, 0}, W * X, H * Z, Y, 0, T_W_G, rng);                 // y = 0, unlabelled
  add_rectangle(mesh, {0, D, 0}, W * X, H * Z, -Y, cls("wall"), T_W_G, rng);      // y = 3, faces -y
  add_box(mesh, {1.5, 1.0, 0.0}, {2.7, 1.8, 0.75}, cls("table"), T_W_G, rng);
  add_box(mesh, {3.0, 0.2, 0.0}, {3.8, 1.6, 0.9}, 0, T_W_G, rng);  // an unlabelled counter
  NavigationConfig config;
  const std::vector<SurfaceNode> surfaces = fit_structural_surfaces(mesh, T_W_G, config);
  struct Expected {
    Eigen::Vector2d normal;
    double offset_m, length_m;
  };
  const std::vector<Expected> expected = {{{1, 0}, 0.0, D}, {{-1, 0}, -W, D}, {{0, 1}, 0.0, W}, {{0, -1}, -D, W}};
  size_t walls = 0;
  for (const SurfaceNode& s : surfaces) walls += s.kind == SurfaceKind::kWall;
  EXPECT_EQ(walls, expected.size());
  for (const Expected& e : expected) {
    const SurfaceNode* match = nullptr;
    for (const SurfaceNode& s : surfaces)
      if (s.kind == SurfaceKind::kWall && s.normal_G.dot(e.normal) > std::cos(2.0 * M_PI / 180)) match = &s;
    ASSERT_NE(match, nullptr) << "no wall facing " << e.normal.transpose();
    EXPECT_NEAR(match->offset_m, e.offset_m, 0.02) << match->id;
    EXPECT_NEAR((match->segment_G[1] - match->segment_G[0]).norm(), e.length_m, 0.25) << match->id;
    EXPECT_GT(match->height_m, H - 0.2) << match->id;
    EXPECT_LT(match->bottom_m, 0.2) << match->id;
    EXPECT_GT(match->area_m2, 0.9 * e.length_m * H) << match->id;
    // The room's centre lies on the wall's room side.
    EXPECT_GT(wall_side_m(*match, {W / 2, D / 2}), 1.0) << match->id;
  }
  const SurfaceNode* ceiling = nullptr;
  for (const SurfaceNode& s : surfaces)
    if (s.kind == SurfaceKind::kCeiling) ceiling = &s;
  ASSERT_NE(ceiling, nullptr);
  EXPECT_NEAR(ceiling->height_m, H, 0.03);
  EXPECT_NEAR(ceiling->area_m2, W * D, 0.1 * W * D);
}

TEST(NavigationStructure, NoCeilingWhenNoneWasSeen) {
  std::mt19937 rng(1);
  TriangleMesh mesh;
  add_rectangle(mesh, {0, 0, 0}, 3 * Eigen::Vector3d::UnitX(), 3 * Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(),
                cls("floor"), Pose::Identity(), rng);
  // A shelf board at 2 m facing up is no ceiling (a ceiling faces down).
  add_rectangle(mesh, {0, 0, 2.0}, 2 * Eigen::Vector3d::UnitX(), 1 * Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(),
                0, Pose::Identity(), rng);
  for (const SurfaceNode& s : fit_structural_surfaces(mesh, Pose::Identity(), NavigationConfig{}))
    EXPECT_NE(s.kind, SurfaceKind::kCeiling) << s.id;
}

namespace {

/// Two 3 x 3 m rooms side by side (x in [0, 3) and [3.2, 6.2)), a 0.2 m wall between them with a
/// door `door_m` wide, outer walls, and a table in the first room (occupied, top class table).
OccupancyGrid two_rooms(double door_m) {
  OccupancyGrid g;
  g.resolution_m = 0.05;
  g.width = 124, g.height = 60;  // 6.2 x 3.0 m
  const size_t n = static_cast<size_t>(g.width) * g.height;
  g.state.assign(n, CellState::kFree);
  g.top_label.assign(n, 0);
  g.top_height_m.assign(n, 0.f);
  for (int iy = 0; iy < g.height; ++iy)
    for (int ix = 0; ix < g.width; ++ix) {
      const Eigen::Vector2d c = g.cell_centre(ix, iy);
      const size_t i = g.index(ix, iy);
      const bool outer = ix == 0 || iy == 0 || ix == g.width - 1 || iy == g.height - 1;
      const bool inner = c.x() >= 3.0 && c.x() < 3.2 && !(c.y() >= 1.0 && c.y() < 1.0 + door_m);
      if (outer || inner) g.state[i] = CellState::kOccupied, g.top_label[i] = cls("wall");
      if (c.x() >= 1.0 && c.x() < 2.0 && c.y() >= 1.0 && c.y() < 2.0)
        g.state[i] = CellState::kOccupied, g.top_label[i] = cls("table");
    }
  return g;
}

ObjectSummary object_at(uint32_t id, ClassId c, const Eigen::Vector3f& centre) {
  ObjectSummary o;
  o.id = id, o.class_id = c, o.centroid = centre;
  for (int k = 0; k < 27; ++k) o.points.push_back(centre + 0.05f * Eigen::Vector3f(k % 3 - 1, k / 3 % 3 - 1, k / 9 - 1));
  return o;
}

}  // namespace

TEST(NavigationStructure, DoorSplitsTwoRoomsIntoTwoPlaces) {
  const OccupancyGrid grid = two_rooms(0.8);
  NavigationConfig config;
  const PlaceMap places = segment_places(grid, config);
  ASSERT_EQ(places.places.size(), 2u);
  // Each room's free cells belong to one place, the other room's to the other.
  size_t agree = 0, free_cells = 0;
  const int left = places.place_of_cell[grid.index(10, 10)], right = places.place_of_cell[grid.index(110, 10)];
  ASSERT_NE(left, right);
  for (int iy = 0; iy < grid.height; ++iy)
    for (int ix = 0; ix < grid.width; ++ix) {
      const size_t i = grid.index(ix, iy);
      const double x = grid.cell_centre(ix, iy).x();
      if (grid.state[i] != CellState::kFree || (x >= 2.8 && x < 3.4)) continue;  // the door's own cells: either
      ++free_cells;
      agree += places.place_of_cell[i] == (x < 3.0 ? left : right);
    }
  EXPECT_GE(static_cast<double>(agree) / free_cells, 0.99) << agree << " of " << free_cells;
  // in_place: a cup on the table (room 1) and a chair in room 2.
  const std::vector<ObjectSummary> objects = {object_at(1, cls("table"), {1.5f, 1.5f, 0.4f}),
                                              object_at(2, cls("cup"), {1.5f, 1.5f, 0.8f}),
                                              object_at(3, cls("chair"), {4.5f, 2.0f, 0.4f})};
  const SceneGraph g = build_scene_graph(objects, grid, {}, config);
  std::map<std::string, std::string> place_of;
  for (const SceneEdge& e : g.edges)
    if (e.relation == Relation::kInPlace) place_of[e.source] = e.target;
  const std::string room1 = "place_" + std::to_string(left), room2 = "place_" + std::to_string(right);
  EXPECT_EQ(place_of["object_1"], room1);
  EXPECT_EQ(place_of["object_2"], room1);
  EXPECT_EQ(place_of["object_3"], room2);
  // One connected edge between the rooms, through the door: 0.8 m wide, centred in it.
  std::vector<const SceneEdge*> connected;
  for (const SceneEdge& e : g.edges)
    if (e.relation == Relation::kConnected) connected.push_back(&e);
  ASSERT_EQ(connected.size(), 1u);
  EXPECT_EQ(std::set<std::string>({connected[0]->source, connected[0]->target}), std::set<std::string>({room1, room2}));
  const double width = connected[0]->evidence.at("passage_width_m").get<double>();
  std::printf("passage %s: %.3f m wide\n", connected[0]->evidence.dump().c_str(), width);
  EXPECT_NEAR(width, 0.8, grid.resolution_m) << width;
  const auto centre = connected[0]->evidence.at("passage_centre_G").get<std::vector<double>>();
  EXPECT_GE(centre[0], 2.8);  // in the door (the wall spans x 3.0-3.2, the door y 1.0-1.8)
  EXPECT_LE(centre[0], 3.4);
  EXPECT_NEAR(centre[1], 1.4, 0.1);
  const SceneGraph again = scene_graph_from_json(to_json(g), "test");
  EXPECT_EQ(to_json(again), to_json(g));
}

// A camera that circled the middle of a room, looking out, saw a ring of floor around an
// unknown middle: one room, one place (unknown space does not narrow it).
TEST(NavigationStructure, RingOfFreeFloorAroundUnknownMiddleIsOnePlace) {
  // A 6 x 6 m room; the unseen middle is an ellipse 5.4 x 2.4 m: the ring is 1.8 m wide above
  // and below it (room cores) and 0.3 m at its ends (narrow: a split if unknown closed the room).
  OccupancyGrid g;
  g.resolution_m = 0.05, g.width = 120, g.height = 120;
  g.state.assign(120 * 120, CellState::kFree);
  g.top_label.assign(g.state.size(), 0);
  g.top_height_m.assign(g.state.size(), 0.f);
  for (int iy = 0; iy < g.height; ++iy)
    for (int ix = 0; ix < g.width; ++ix) {
      const Eigen::Vector2d d = g.cell_centre(ix, iy) - Eigen::Vector2d(3.0, 3.0);
      const size_t i = g.index(ix, iy);
      if (ix == 0 || iy == 0 || ix == g.width - 1 || iy == g.height - 1)
        g.state[i] = CellState::kOccupied, g.top_label[i] = cls("wall");
      else if (std::pow(d.x() / 2.7, 2) + std::pow(d.y() / 1.2, 2) < 1.0)
        g.state[i] = CellState::kUnknown;
    }
  const PlaceMap places = segment_places(g, NavigationConfig{});
  EXPECT_EQ(places.places.size(), 1u);
  EXPECT_TRUE(places.passages.empty());  // a single room has no passage
}

TEST(NavigationStructure, WideOpeningAndNoSplitGiveOnePlace) {
  NavigationConfig config;
  const PlaceMap open = segment_places(two_rooms(1.6), config);
  EXPECT_EQ(open.places.size(), 1u);  // an opening, not a door
  EXPECT_TRUE(open.passages.empty());
  const SceneGraph g = build_scene_graph({}, two_rooms(1.6), {}, config);
  EXPECT_EQ(std::count_if(g.edges.begin(), g.edges.end(), [](const SceneEdge& e) { return e.relation == Relation::kConnected; }), 0);
  config.place_passage_width_m = 0.0;
  EXPECT_EQ(segment_places(two_rooms(0.8), config).places.size(), 1u);  // connected: one region
}
