// Issue 39's checks on real data, no ground truth needed: 7-Scenes redkitchen (every 2nd of its
// 500 frames) mapped as `semap run` maps it, with the default models and estimated poses. Read
// from the output files as a robot stack reads them (map.pgm + map.yaml, scene_graph.json,
// trajectory.txt):
//   - every cell the camera passed over (the trajectory projected to the floor) is free or
//     unknown, never occupied;
//   - the cells under the table top are occupied;
//   - the walls bound the free space: no free cell lies behind a wall within its span, and the
//     cameras are on the room side of every wall;
//   - the cups are `on` the table, the table `on` the floor, nothing is `on` (or any relation
//     to) a wall or the ceiling;
//   - the 3D distance field (map.semap + the camera positions) finds every camera position in
//     observed free space, most of them farther from any surface than the TSDF's truncation.
// SEMAP_NAVIGATION_REAL_KEEP=DIR keeps a copy of the run's output folder there (to look at it
// with `semap view DIR`).
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <opencv2/imgcodecs.hpp>

#include "semap/io/trajectory_io.hpp"
#include "semap/navigation/distance_query.hpp"
#include "semap/navigation/scene_graph.hpp"
#include "semap/pipeline/run_pipeline.hpp"
#include "sequence_slices.hpp"
#include "shared_fixture.hpp"
#include "test_support.hpp"
#include "tsdf/map_io.hpp"

namespace semap {
namespace {

/// map.pgm + map.yaml read as map_server does (0 = occupied, 254 = free, else unknown).
struct MapFile {
  cv::Mat image;  // row 0: highest y
  double resolution_m = 0.0;
  Eigen::Vector2d origin_G = Eigen::Vector2d::Zero();
  Pose T_W_G = Pose::Identity();

  /// Pixel value under a gravity-frame (x, y); 205 (unknown) outside the image.
  int value_at(const Eigen::Vector2d& xy_G) const {
    const Eigen::Vector2d c = (xy_G - origin_G) / resolution_m;
    const int col = static_cast<int>(std::floor(c.x())), row = image.rows - 1 - static_cast<int>(std::floor(c.y()));
    if (col < 0 || row < 0 || col >= image.cols || row >= image.rows) return 205;
    return image.at<uint8_t>(row, col);
  }
  Eigen::Vector2d cell_centre(int row, int col) const {
    return origin_G + Eigen::Vector2d(col + 0.5, image.rows - 1 - row + 0.5) * resolution_m;
  }
};

MapFile read_map(const std::filesystem::path& out) {
  MapFile m;
  const YAML::Node yaml = YAML::LoadFile((out / "map.yaml").string());
  m.image = cv::imread((out / yaml["image"].as<std::string>()).string(), cv::IMREAD_UNCHANGED);
  m.resolution_m = yaml["resolution"].as<double>();
  m.origin_G = {yaml["origin"][0].as<double>(), yaml["origin"][1].as<double>()};
  for (int k = 0; k < 16; ++k) m.T_W_G.matrix()(k / 4, k % 4) = yaml["T_W_G"][k].as<double>();
  return m;
}

const SceneObjectNode* node(const SceneGraph& g, const std::string& id) {
  for (const SceneObjectNode& o : g.objects)
    if (object_node_id(o.id) == id) return &o;
  return nullptr;
}

class NavigationReal : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const std::filesystem::path dataset = test::data_dir() / "7scenes_redkitchen";
    const std::filesystem::path semantic = test::models_dir() / kDefaultSemanticModel;
    const std::filesystem::path instance = test::models_dir() / kDefaultInstanceModels[0];
    if (!std::filesystem::exists(dataset) || !std::filesystem::exists(semantic) || !std::filesystem::exists(instance))
      return;
    dir_ = new test::TempDir("semap_navigation_real");
    const std::filesystem::path out = dir_->path() / "out";
    // One run per build of this binary, not one per test process (tests/shared_fixture.hpp).
    test::copy_shared_fixture("navigation_real_redkitchen_step_2", "/proc/self/exe", [&](const std::filesystem::path& to) {
      const test::TempDir slice("semap_navigation_real_slice");
      test::SliceSpec spec;
      spec.step = 2;
      test::write_sequence_slice(dataset, spec, slice.path() / "data");
      RunOptions options;
      options.dataset = slice.path() / "data";
      options.out_dir = to;
      options.segmenter = "panoptic:" + semantic.string() + "+" + instance.string();  // the default models
      options.show_progress = false;
      run_pipeline(options, SemapConfig{});
    }, out);
    if (!std::filesystem::exists(out / "map.semap")) return;  // the fixture failed (reported)
    map_ = new MapFile(read_map(out));
    graph_ = new SceneGraph(load_scene_graph(out));
    trajectory_ = new Trajectory(read_tum_trajectory(out / "trajectory.txt"));
    tsdf_ = new TsdfMap(load_map(out / "map.semap"));
    if (const char* keep = std::getenv("SEMAP_NAVIGATION_REAL_KEEP"))
      std::filesystem::copy(out, keep, std::filesystem::copy_options::recursive);
  }
  static void TearDownTestSuite() {
    delete tsdf_, delete trajectory_, delete graph_, delete map_, delete dir_;
  }
  void SetUp() override {
    if (!map_) SEMAP_SKIP_OR_FAIL("7scenes_redkitchen or the default models missing (SEMAP_DATA_DIR / SEMAP_MODELS_DIR)");
  }
  static inline test::TempDir* dir_ = nullptr;
  static inline MapFile* map_ = nullptr;
  static inline SceneGraph* graph_ = nullptr;
  static inline Trajectory* trajectory_ = nullptr;
  static inline TsdfMap* tsdf_ = nullptr;
};

TEST_F(NavigationReal, CellsUnderTheCameraAreNeverOccupied) {
  const Pose T_G_W = map_->T_W_G.inverse();
  size_t occupied = 0, free = 0, inside = 0;
  for (const auto& pose : *trajectory_) {
    const Eigen::Vector2d xy_G = (T_G_W * pose.T_world_camera.translation()).head<2>();
    const Eigen::Vector2d c = (xy_G - map_->origin_G) / map_->resolution_m;
    inside += c.x() >= 0 && c.y() >= 0 && c.x() < map_->image.cols && c.y() < map_->image.rows;
    const int v = map_->value_at(xy_G);
    occupied += v == 0, free += v == 254;
  }
  std::printf("trajectory over the floor: %zu poses, %zu within the grid's extent, %zu over free cells, %zu over "
              "occupied ones\n",
              trajectory_->size(), inside, free, occupied);
  EXPECT_EQ(occupied, 0u);
  EXPECT_GE(inside, trajectory_->size() / 10) << "the check needs the camera over the mapped area";
}

TEST_F(NavigationReal, CellsUnderTheTableTopAreOccupied) {
  const SceneObjectNode* table = nullptr;
  for (const SceneObjectNode& o : graph_->objects)
    if (o.class_name == "table" && (!table || o.point_count > table->point_count)) table = &o;
  ASSERT_NE(table, nullptr) << "no table in the scene graph";
  GravityBox inner = table->box;  // 10 cm in from the box's sides
  inner.size_m.head<2>() -= Eigen::Vector2d::Constant(0.2);
  size_t inside = 0, occupied = 0;
  for (int row = 0; row < map_->image.rows; ++row)
    for (int col = 0; col < map_->image.cols; ++col)
      if (inner.footprint_contains(map_->cell_centre(row, col)))
        ++inside, occupied += map_->image.at<uint8_t>(row, col) == 0;
  std::printf("table %.2f x %.2f m, top %.2f m: %zu of %zu cells under it occupied\n", table->box.size_m.x(),
              table->box.size_m.y(), table->box.top_m(), occupied, inside);
  ASSERT_GT(inside, 20u);
  EXPECT_GE(static_cast<double>(occupied) / inside, 0.9);
}

TEST_F(NavigationReal, WallsBoundTheFreeSpace) {
  std::vector<const SurfaceNode*> walls;
  for (const SurfaceNode& s : graph_->surfaces)
    if (s.kind == SurfaceKind::kWall) walls.push_back(&s);
  std::printf("%zu walls\n", walls.size());
  ASSERT_GE(walls.size(), 2u);
  const Pose T_G_W = map_->T_W_G.inverse();
  for (const SurfaceNode* w : walls) {
    // Free cells within the wall's span: in front of it, never more than 15 cm behind it.
    size_t in_span = 0, behind = 0;
    for (int row = 0; row < map_->image.rows; ++row)
      for (int col = 0; col < map_->image.cols; ++col) {
        if (map_->image.at<uint8_t>(row, col) != 254) continue;
        const Eigen::Vector2d c = map_->cell_centre(row, col);
        const double along = along_wall(*w, c);
        if (along < 0.0 || along > 1.0) continue;
        ++in_span, behind += wall_side_m(*w, c) < -0.15;
      }
    size_t cameras_in_span = 0, cameras_behind = 0;
    for (const auto& pose : *trajectory_) {
      const Eigen::Vector2d c = (T_G_W * pose.T_world_camera.translation()).head<2>();
      const double along = along_wall(*w, c);
      if (along < 0.0 || along > 1.0) continue;
      ++cameras_in_span, cameras_behind += wall_side_m(*w, c) < 0.0;
    }
    std::printf("%s: %.1f m long, %.2f..%.2f m high, %.2f m2: %zu of %zu free cells behind, %zu of %zu cameras behind\n",
                w->id.c_str(), (w->segment_G[1] - w->segment_G[0]).norm(), w->bottom_m, w->height_m, w->area_m2, behind,
                in_span, cameras_behind, cameras_in_span);
    EXPECT_LE(behind, in_span / 100) << w->id;
    EXPECT_EQ(cameras_behind, 0u) << w->id;
  }
}

// Cups and laptops over the table rest on it (YOLO's "laptops" in redkitchen stand on the counter
// at the back, which is no object: they rest on nothing the graph knows; printed, not checked).
TEST_F(NavigationReal, CupsOnTheTableTableOnTheFloorNothingOnAWall) {
  std::map<std::string, std::string> support;
  for (const SceneEdge& e : graph_->edges) {
    if (e.relation == Relation::kOn) support[e.source] = e.target;
    EXPECT_FALSE(e.target.starts_with("wall") || e.target == "ceiling") << e.source << " -> " << e.target;
  }
  std::vector<const SceneObjectNode*> tables;
  for (const SceneObjectNode& o : graph_->objects)
    if (o.class_name == "table") tables.push_back(&o);
  ASSERT_FALSE(tables.empty());
  size_t over_table = 0;
  for (const SceneObjectNode& o : graph_->objects) {
    const std::string id = object_node_id(o.id);
    const SceneObjectNode* below = node(*graph_, support[id]);
    std::printf("%s %s at (%.2f, %.2f), bottom %.2f m: on %s (%s)\n", id.c_str(), o.class_name.c_str(), o.box.center_G.x(),
                o.box.center_G.y(), o.box.bottom_m(), support[id].c_str(), below ? below->class_name.c_str() : "-");
    if (o.class_name == "table") EXPECT_EQ(support[id], "floor") << id;
    if (o.class_name != "cup" && o.class_name != "laptop") continue;
    const bool over = std::any_of(tables.begin(), tables.end(), [&](const SceneObjectNode* t) {
      return t->box.footprint_contains(o.box.center_G.head<2>(), 0.1) && o.box.bottom_m() > t->box.center_G.z();
    });
    if (!over) continue;
    ++over_table;
    EXPECT_TRUE(below && below->class_name == "table") << id << " " << o.class_name << " is on '" << support[id] << "'";
  }
  EXPECT_GE(over_table, 1u) << "no cup or laptop over the table";
}

// Where the camera was is free space: the distance field must say so (observed, no surface
// within a few centimetres), and measure it beyond the TSDF's truncation band where the camera
// stood in the open (the clamped TSDF query it replaced read at most 8 cm, or NaN there).
TEST_F(NavigationReal, CameraPositionsLieInObservedFreeSpace) {
  std::vector<Eigen::Vector3d> cameras;
  for (const auto& pose : *trajectory_) cameras.push_back(pose.T_world_camera.translation());
  const DistanceQuery query(*tsdf_, NavigationConfig{}, cameras);
  const double truncation = tsdf_->config().truncation();
  size_t observed = 0, free_5cm = 0, beyond_truncation = 0;
  std::vector<double> d;
  for (const Eigen::Vector3d& c : cameras) {
    const double di = query.distance_m(c);
    if (std::isnan(di)) {
      std::printf("unobserved camera position (%.3f, %.3f, %.3f)\n", c.x(), c.y(), c.z());
      continue;
    }
    ++observed, d.push_back(di);
    free_5cm += query.is_free(c, 0.05);
    beyond_truncation += di > truncation;
  }
  std::sort(d.begin(), d.end());
  const EsdfStats& st = query.esdf().stats();
  std::printf("camera positions: %zu, observed %zu, free for a 5 cm ball %zu, beyond the truncation (%.2f m) %zu; "
              "distance min %.3f median %.3f m; field built in %.2f s, %d x %d x %d cells\n",
              cameras.size(), observed, free_5cm, truncation, beyond_truncation, d.empty() ? NAN : d.front(),
              d.empty() ? NAN : d[d.size() / 2], st.build_s, st.dims.x(), st.dims.y(), st.dims.z());
  EXPECT_EQ(observed, cameras.size());
  EXPECT_GE(free_5cm, observed * 95 / 100);
  EXPECT_GT(beyond_truncation, observed / 2);
}

}  // namespace
}  // namespace semap
