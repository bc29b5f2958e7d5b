// Issue 39 on the synthetic world, where the ground truth is known: the occupancy grid's cells
// against the scene's geometry (scene.json primitives and the room's walls), and the scene
// graph's `on` edges against each object's support in scene.json. One ground-truth-pose,
// ground-truth-segmentation run through run_pipeline (the `semap run` path) feeds both tests.
#include <gtest/gtest.h>

#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "core/progress.hpp"
#include "semap/io/ply_io.hpp"
#include "semap/navigation/scene_graph.hpp"
#include "semap/pipeline/run_pipeline.hpp"
#include "synthetic_room.hpp"
#include "test_support.hpp"

using namespace semap;

namespace {

struct GtBox {
  Eigen::Vector3d center, extent;
  Eigen::Matrix3d rotation;
  bool contains(const Eigen::Vector3d& p, double margin) const {
    const Eigen::Vector3d local = rotation.transpose() * (p - center);
    for (int i = 0; i < 3; ++i)
      if (std::abs(local[i]) > extent[i] / 2 + margin) return false;
    return true;
  }
};

GtBox gt_box(const nlohmann::json& j) {
  GtBox b;
  for (int i = 0; i < 3; ++i) b.center[i] = j["center"][i], b.extent[i] = j["extent"][i];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) b.rotation(r, c) = j["rotation"][3 * r + c];
  return b;
}

struct GtScene {
  Eigen::Vector3d room_size;
  std::vector<GtBox> solids;                 // every primitive (objects and stuff)
  std::map<int, GtBox> object_boxes;         // instance id -> tight box
  std::map<int, std::string> support;        // instance id -> floor | wall | on:<id>
};

GtScene load_scene(const std::filesystem::path& file) {
  std::ifstream in(file);
  const nlohmann::json j = nlohmann::json::parse(in);
  GtScene s;
  for (int i = 0; i < 3; ++i) s.room_size[i] = j["room"]["size"][i];
  for (const auto& o : j["objects"]) {
    s.object_boxes[o["instance_id"]] = gt_box(o["obb"]);
    s.support[o["instance_id"]] = o["support"];
    for (const auto& p : o["primitives"]) s.solids.push_back(gt_box(p));
  }
  for (const auto& p : j["stuff"]) s.solids.push_back(gt_box(p));
  return s;
}

class NavigationSynth : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    Progress::set_mode(-1);
    dir_ = new test::TempDir("semap_navigation");
    test::copy_small_synthetic_room(dir_->path() / "data");  // the pipeline suite's room
    RunOptions o;
    o.dataset = dir_->path() / "data";
    o.out_dir = dir_->path() / "out";
    o.poses = PoseSource::groundtruth;
    o.segmenter = "groundtruth";
    o.show_progress = false;
    o.evaluate = false;
    SemapConfig config;
    config.tsdf.voxel_size = 0.02;
    run_pipeline(o, config);
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static std::filesystem::path out() { return dir_->path() / "out"; }
  static GtScene scene() { return load_scene(dir_->path() / "data" / "scene.json"); }
  static test::TempDir* dir_;
};
test::TempDir* NavigationSynth::dir_ = nullptr;

/// Whether a solid (a primitive, or the outside of the room) holds a point of the cell's
/// vertical centre line within the height band, each solid grown by `margin_m` (negative:
/// shrunk).
bool gt_column_occupied(const GtScene& s, const Pose& T_W_G, const Eigen::Vector2d& xy_G, double lo_m, double hi_m,
                        double margin_m) {
  for (double z = lo_m; z <= hi_m; z += 0.01) {
    const Eigen::Vector3d p = T_W_G * Eigen::Vector3d(xy_G.x(), xy_G.y(), z);
    const bool outside_room = p.x() < margin_m || p.y() < margin_m || p.x() > s.room_size.x() - margin_m ||
                              p.y() > s.room_size.y() - margin_m;
    if (outside_room) return true;
    for (const GtBox& b : s.solids)
      if (b.contains(p, margin_m)) return true;
  }
  return false;
}

}  // namespace

// Every observed (free or occupied) cell whose state the geometry decides (no surface of the
// scene passes within half a cell + one voxel of its centre line) agrees with the scene.
TEST_F(NavigationSynth, GridCellsAgreeWithSceneGeometry) {
  const GtScene s = scene();
  // Read the grid back from the files as a user would: map.yaml + map.pgm.
  std::ifstream yaml(out() / "map.yaml");
  ASSERT_TRUE(yaml) << "map.yaml missing";
  std::string line;
  double resolution = 0, ox = 0, oy = 0, min_h = 0, max_h = 0;
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  while (std::getline(yaml, line)) {
    if (line.rfind("resolution: ", 0) == 0) resolution = std::stod(line.substr(12));
    if (line.rfind("origin: [", 0) == 0) std::sscanf(line.c_str(), "origin: [%lf, %lf", &ox, &oy);
    if (line.rfind("min_height_m: ", 0) == 0) min_h = std::stod(line.substr(14));
    if (line.rfind("max_height_m: ", 0) == 0) max_h = std::stod(line.substr(14));
    if (line.rfind("T_W_G: [", 0) == 0) {
      std::stringstream values(line.substr(8));
      for (int i = 0; i < 16; ++i) {
        values >> T(i / 4, i % 4);
        values.ignore(2);
      }
    }
  }
  ASSERT_GT(resolution, 0.0);
  Pose T_W_G;
  T_W_G.matrix() = T;
  std::ifstream pgm(out() / "map.pgm", std::ios::binary);
  std::string magic;
  int w = 0, h = 0, maxval = 0;
  pgm >> magic >> w >> h >> maxval;
  pgm.get();
  ASSERT_EQ(magic, "P5");
  std::vector<uint8_t> pixels(static_cast<size_t>(w) * h);
  pgm.read(reinterpret_cast<char*>(pixels.data()), pixels.size());
  ASSERT_TRUE(pgm) << "map.pgm truncated";
  const double voxel = 0.02, ambiguity = resolution / 2 + voxel;
  size_t observed = 0, decided = 0, agree = 0, free_cells = 0, occupied_cells = 0;
  for (int row = 0; row < h; ++row)
    for (int ix = 0; ix < w; ++ix) {
      const uint8_t v = pixels[static_cast<size_t>(row) * w + ix];
      if (v == 205) continue;
      ++observed;
      const bool occupied = v == 0;
      (occupied ? occupied_cells : free_cells)++;
      const int iy = h - 1 - row;  // map_server: the last image row is the origin's
      const Eigen::Vector2d xy(ox + (ix + 0.5) * resolution, oy + (iy + 0.5) * resolution);
      const bool gt_grown = gt_column_occupied(s, T_W_G, xy, min_h, max_h, ambiguity);
      const bool gt_shrunk = gt_column_occupied(s, T_W_G, xy, min_h + voxel, max_h - voxel, -ambiguity);
      if (gt_grown != gt_shrunk) continue;  // a surface passes through or beside the cell
      ++decided;
      agree += occupied == gt_grown;
    }
  const double agreement = decided ? double(agree) / decided : 0.0;
  std::cout << "grid " << w << "x" << h << " at " << resolution << " m: " << free_cells << " free, " << occupied_cells
            << " occupied; " << decided << " of " << observed << " observed cells decided by the geometry; agreement "
            << agreement << "\n";
  EXPECT_GT(free_cells, 1000u);
  EXPECT_GT(occupied_cells, 200u);
  EXPECT_GT(decided, observed / 2);
  EXPECT_GE(agreement, 0.95);
}

// `on` edges against scene.json supports: each mapped object is matched to the ground-truth
// instance holding most of its points (at least half of them).
TEST_F(NavigationSynth, OnEdgesMatchSceneSupports) {
  const GtScene s = scene();
  const SceneGraph graph = load_scene_graph(out());
  std::map<std::string, int> gt_of_node;  // scene graph node id -> gt instance (floor: 0)
  gt_of_node["floor"] = 0;
  std::set<int> matched_gt;
  for (const SceneObjectNode& o : graph.objects) {
    const TriangleMesh cloud = read_ply(out() / "objects" / (std::to_string(o.id) + ".ply"));
    std::map<int, size_t> votes;
    for (const Eigen::Vector3f& p : cloud.vertices.points)
      for (const auto& [id, box] : s.object_boxes)
        if (box.contains(p.cast<double>(), 0.03)) {
          ++votes[id];
          break;
        }
    for (const auto& [id, n] : votes)
      if (2 * n >= cloud.vertices.points.size() && !matched_gt.count(id)) {
        gt_of_node[object_node_id(o.id)] = id;
        matched_gt.insert(id);
      }
  }
  auto gt_target = [&](int id) {  // the ground-truth support of instance id as an instance (floor 0), or -1
    const std::string& sup = s.support.at(id);
    if (sup == "floor") return 0;
    if (sup.rfind("on:", 0) == 0) return std::stoi(sup.substr(3));
    return -1;
  };
  size_t predicted = 0, correct = 0;
  std::set<int> found;  // gt instances whose support edge was found
  for (const SceneEdge& e : graph.edges) {
    if (e.relation != Relation::kOn || !gt_of_node.count(e.source)) continue;
    const int src = gt_of_node[e.source];
    const int target = gt_of_node.count(e.target) ? gt_of_node[e.target] : -2;
    ++predicted;
    if (gt_target(src) == target) ++correct, found.insert(src);
    else
      std::cout << "wrong: " << e.source << " (gt " << src << ") on " << e.target << " " << e.evidence.dump() << "\n";
  }
  size_t expected = 0;
  for (int id : matched_gt) {
    const int t = gt_target(id);
    if (t < 0 || (t > 0 && !matched_gt.count(t))) continue;  // wall-mounted, or its support was not mapped
    ++expected;
    if (!found.count(id)) std::cout << "missed: gt " << id << " on " << s.support.at(id) << "\n";
  }
  const double precision = predicted ? double(correct) / predicted : 0.0;
  const double recall = expected ? double(found.size()) / expected : 0.0;
  std::cout << graph.objects.size() << " objects, " << matched_gt.size() << " matched to ground truth; on edges: "
            << predicted << " predicted, " << correct << " correct, " << expected << " expected; precision " << precision
            << ", recall " << recall << "\n";
  EXPECT_GE(matched_gt.size(), 6u);
  EXPECT_GE(expected, 6u);
  EXPECT_GE(precision, 0.9);
  EXPECT_GE(recall, 0.9);
}
