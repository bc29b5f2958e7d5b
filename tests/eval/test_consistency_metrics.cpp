// Ground-truth-free semantic consistency (issue 38) on synthetic rooms whose answer is known.
#include <gtest/gtest.h>

#include "core/synthetic_room.hpp"
#include "semap/core/error.hpp"
#include "semap/eval/consistency_metrics.hpp"
#include "semap/io/ply_io.hpp"
#include "semap/io/trajectory_io.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

using test::handheld_trajectory;
using test::room_mesh;
using test::RoomParts;

/// Relabels every vertex of `mesh` from index `first` on (the parts added after it).
void relabel_from(TriangleMesh& mesh, size_t first, Label label) {
  for (size_t i = first; i < mesh.vertices.labels.size(); ++i) mesh.vertices.labels[i] = id(label);
}

double mesh_area(const TriangleMesh& mesh) {
  double area = 0.0;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) area += triangle_geometry(mesh, t).area_m2;
  return area;
}

TEST(Consistency, CorrectlyLabelledRoom) {
  const SemanticConsistency c = evaluate_consistency(room_mesh(), handheld_trajectory());
  EXPECT_GT(c.labelled_area_share, 0.999);
  EXPECT_GT(c.floor.agreement, 0.99);
  EXPECT_GT(c.floor.facing_agreement, 0.99);
  EXPECT_GT(c.ceiling.agreement, 0.99);
  EXPECT_GT(c.ceiling.facing_agreement, 0.99);
  EXPECT_GT(c.wall.agreement, 0.99);
  ASSERT_TRUE(c.floor_thickness_m.has_value());
  EXPECT_LT(*c.floor_thickness_m, 0.02);  // 5 mm vertex noise
  EXPECT_NEAR(*c.floor_height_low_m, 0.0, 0.02);
  // Walls (45 m^2) > floor = ceiling (20 m^2) > table (~1 m^2).
  ASSERT_GE(c.classes.size(), 4u);
  EXPECT_EQ(c.classes[0].class_id, id(Label::kWall));
  EXPECT_NEAR(c.classes[0].area_share, 45.0 / 85.96, 0.02);
  EXPECT_TRUE(c.gravity.floor_found);
}

TEST(Consistency, TableTopLabelledFloorThickensTheFloor) {
  TriangleMesh mesh = room_mesh({.table = false});
  // A 5 m^2 table top (20 % of the floor-labelled area) at 0.75 m, called floor.
  test::add_rectangle(mesh, {1.0, 1.0, 0.75}, {2.5, 0, 0}, {0, 2.0, 0}, Label::kFloor, 0.1, 0.005);
  const SemanticConsistency c = evaluate_consistency(mesh, handheld_trajectory());
  ASSERT_TRUE(c.floor_thickness_m.has_value());
  EXPECT_NEAR(*c.floor_thickness_m, 0.75, 0.03);
  EXPECT_GT(c.floor.agreement, 0.99);  // still horizontal: only the thickness tells
  ASSERT_TRUE(c.gravity.floor_found);
  EXPECT_NEAR(c.gravity.floor_height_m, 0.0, 0.015);  // the floor, not the table top
}

TEST(Consistency, WallLabelledFloorLowersFloorAgreement) {
  TriangleMesh mesh = room_mesh({.walls = false, .noise_m = 0.0});
  const double floor_area = 20.0, wall_area = 5.0 * 2.5;
  const size_t first = mesh.vertices.size();
  test::add_rectangle(mesh, {0, 0, 0}, {5, 0, 0}, {0, 0, 2.5}, Label::kWall);
  relabel_from(mesh, first, Label::kFloor);
  const SemanticConsistency c = evaluate_consistency(mesh, handheld_trajectory());
  EXPECT_NEAR(c.floor.area_m2, floor_area + wall_area, 1e-3);
  EXPECT_NEAR(c.floor.agreement, floor_area / (floor_area + wall_area), 0.005);
  EXPECT_NEAR(c.floor.area_share, (floor_area + wall_area) / mesh_area(mesh), 1e-6);
  EXPECT_EQ(c.wall.area_m2, 0.0);
}

TEST(Consistency, CeilingLabelledFloorFacesTheWrongWay) {
  TriangleMesh mesh = room_mesh({.ceiling = false, .noise_m = 0.0});
  const size_t first = mesh.vertices.size();
  test::add_rectangle(mesh, {0, 0, 2.5}, {5, 0, 0}, {0, 4, 0}, Label::kCeiling, 0.1, 0.0, true);
  relabel_from(mesh, first, Label::kFloor);
  const SemanticConsistency c = evaluate_consistency(mesh, handheld_trajectory());
  EXPECT_GT(c.floor.agreement, 0.99);                  // horizontal
  EXPECT_NEAR(c.floor.facing_agreement, 0.5, 0.01);  // half of it faces down
  EXPECT_NEAR(*c.floor_thickness_m, 2.5, 0.01);
}

TEST(Consistency, UnlabelledAreaAndTopClasses) {
  TriangleMesh mesh = room_mesh({.ceiling = false, .noise_m = 0.0});
  const size_t first = mesh.vertices.size();
  test::add_rectangle(mesh, {0, 0, 2.5}, {5, 0, 0}, {0, 4, 0}, Label::kCeiling, 0.1, 0.0, true);
  relabel_from(mesh, first, Label::kUnlabelled);
  const SemanticConsistency c = evaluate_consistency(mesh, handheld_trajectory(), {.top_classes = 2});
  EXPECT_NEAR(c.labelled_area_share, 1.0 - 20.0 / mesh_area(mesh), 1e-6);
  EXPECT_EQ(c.ceiling.area_m2, 0.0);
  ASSERT_EQ(c.classes.size(), 2u);
  EXPECT_EQ(c.classes[1].class_id, id(Label::kFloor));
  const nlohmann::json j = to_json(c);
  EXPECT_TRUE(j["ceiling"]["agreement"].is_null());
  EXPECT_EQ(j["class_area_share"].size(), 2u);
  EXPECT_EQ(j["gravity"]["method"], "trajectory+floor_labels");

  // No labels at all: nothing labelled, no floor thickness.
  mesh.vertices.labels.clear();
  const SemanticConsistency none = evaluate_consistency(mesh, handheld_trajectory());
  EXPECT_EQ(none.labelled_area_share, 0.0);
  EXPECT_FALSE(none.floor_thickness_m.has_value());
  EXPECT_TRUE(to_json(none)["floor_thickness_m"].is_null());
}

TEST(Consistency, FolderErrorsNameTheFile) {
  test::TempDir dir("semap_consistency");
  auto message = [](const std::filesystem::path& out) {
    try {
      evaluate_consistency_folder(out);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message(dir / "missing").find("missing"), std::string::npos);
  EXPECT_NE(message(dir.path()).find("mesh.ply"), std::string::npos);
  test::write_text(dir / "mesh.ply", "ply\nformat ascii 1.0\nelement vertex 3\n");
  EXPECT_NE(message(dir.path()).find("mesh.ply"), std::string::npos);

  // A good mesh without trajectory.txt: the floor labels give up.
  write_ply(dir / "mesh.ply", room_mesh());
  const SemanticConsistency c = evaluate_consistency_folder(dir.path());
  EXPECT_EQ(c.gravity.method, GravityMethod::kFloorLabels);
  EXPECT_GT(c.floor.agreement, 0.99);
  test::write_text(dir / "trajectory.txt", "0 1 2\n");
  EXPECT_NE(message(dir.path()).find("trajectory.txt"), std::string::npos);
}

}  // namespace
}  // namespace semap
