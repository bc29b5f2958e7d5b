// Object metrics (WOv, counts, P/R) on ground-truth-derived object maps.
#include <gtest/gtest.h>

#include <limits>
#include <random>

#include <nlohmann/json.hpp>

#include "semap/core/error.hpp"
#include "semap/eval/object_metrics.hpp"
#include "semap/io/ply_io.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

const ClassId kChair = id(Label::kChair), kTable = id(Label::kTable), kCup = id(Label::kCup);

// Box faces on round coordinates would sit exactly on voxel borders, where float rounding
// flips whole faces into the neighbouring voxel layer; real scenes are not grid-aligned.
const Eigen::Vector3f kGridOffset(0.0037f, 0.0061f, 0.0043f);

// Surface points of an axis-aligned box every 1 cm.
void add_box(PointCloud& cloud, Eigen::Vector3f lo, Eigen::Vector3f hi, ClassId label, uint32_t instance,
             const Eigen::Vector3f& offset = kGridOffset) {
  const float s = 0.01f;
  lo += offset;
  hi += offset;
  for (float x = lo.x(); x <= hi.x() + 1e-6f; x += s)
    for (float y = lo.y(); y <= hi.y() + 1e-6f; y += s)
      for (float z = lo.z(); z <= hi.z() + 1e-6f; z += s) {
        const bool on_surface = x - lo.x() < s * 0.5f || hi.x() - x < s * 0.5f || y - lo.y() < s * 0.5f ||
                                hi.y() - y < s * 0.5f || z - lo.z() < s * 0.5f || hi.z() - z < s * 0.5f;
        if (!on_surface) continue;
        cloud.points.emplace_back(x, y, z);
        cloud.labels.push_back(label);
        cloud.instances.push_back(instance);
      }
}

// Two chairs side by side (different sizes), a table, a cup, and a floor (stuff, instance 0).
PointCloud make_gt_points() {
  PointCloud cloud;
  add_box(cloud, {0.0f, 0.0f, 0.0f}, {0.5f, 0.5f, 0.9f}, kChair, 1);
  add_box(cloud, {0.6f, 0.0f, 0.0f}, {1.0f, 0.4f, 0.8f}, kChair, 2);
  add_box(cloud, {2.0f, 0.0f, 0.0f}, {3.2f, 0.8f, 0.75f}, kTable, 3);
  add_box(cloud, {2.2f, 0.2f, 0.80f}, {2.28f, 0.28f, 0.9f}, kCup, 4);
  for (float x = 0; x < 4; x += 0.02f)
    for (float y = 0; y < 2; y += 0.02f) {
      cloud.points.emplace_back(x, y, -0.05f);
      cloud.labels.push_back(id(Label::kFloor));
      cloud.instances.push_back(0);
    }
  return cloud;
}

double expected_wov_without(const ObjectEvaluation& e, uint32_t gt_id) {
  double num = 0, den = 0;
  for (const auto& g : e.per_gt) {
    den += static_cast<double>(g.voxels);
    if (g.gt_id != gt_id) num += static_cast<double>(g.voxels);
  }
  return num / den;
}

TEST(ObjectMetrics, GroundTruthAgainstItself) {
  const auto gt = gt_objects_from_points(make_gt_points());
  ASSERT_EQ(gt.size(), 4u);
  EXPECT_EQ(gt[0].class_id, kChair);
  EXPECT_EQ(gt[3].class_id, kCup);
  const ObjectEvaluation e = evaluate_objects(gt, gt);
  EXPECT_DOUBLE_EQ(e.wov, 1.0);
  EXPECT_DOUBLE_EQ(e.wov_same_class, 1.0);
  ASSERT_EQ(e.matches.size(), 2u);
  for (const auto& m : e.matches) {
    EXPECT_EQ(m.true_positives, 4u);
    EXPECT_DOUBLE_EQ(m.precision, 1.0);
    EXPECT_DOUBLE_EQ(m.recall, 1.0);
  }
  ASSERT_EQ(e.counts.size(), 3u);
  for (const auto& c : e.counts) EXPECT_EQ(c.gt, c.map) << int(c.class_id);
}

// Synthetic worlds (and many built ones) put faces at round coordinates, which a voxel grid with
// its origin at 0 has on its cell borders. A map that reproduces such faces to 0.1 mm must still
// score (almost) 1: the evaluation grid's origin must not sit on round coordinates.
TEST(ObjectMetrics, PerfectMapOfGridAlignedFacesScoresOne) {
  PointCloud cloud;
  const Eigen::Vector3f none = Eigen::Vector3f::Zero();
  add_box(cloud, {0.0f, 0.0f, 0.0f}, {0.5f, 0.5f, 0.9f}, kChair, 1, none);
  add_box(cloud, {2.0f, 0.0f, 0.40f}, {3.2f, 0.8f, 0.62f}, kTable, 2, none);
  add_box(cloud, {2.2f, 0.2f, 0.62f}, {2.28f, 0.28f, 0.75f}, kCup, 3, none);
  const auto gt = gt_objects_from_points(cloud);
  auto map = gt;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> jitter(-1e-4f, 1e-4f);
  for (auto& o : map)
    for (auto& p : o.points) p += Eigen::Vector3f(jitter(rng), jitter(rng), jitter(rng));
  const ObjectEvaluation e = evaluate_objects(gt, map);
  EXPECT_GT(e.wov, 0.99);
  for (const auto& g : e.per_gt) EXPECT_GT(g.best_iou, 0.98) << g.gt_id;
}

// A map a few millimetres off the truth (depth noise, a fused surface 3 mm high) is the same
// surface at the map's resolution and scores 1; the voxel-set IoU (wov_voxel) moves half a
// horizontal face into the next voxel layer when the truth lies just under a voxel border.
TEST(ObjectMetrics, SubVoxelOffsetKeepsTheSurfaceIouButNotTheVoxelIou) {
  PointCloud cloud;
  add_box(cloud, {2.0f, 0.0f, 0.40f}, {3.2f, 0.8f, 0.41f}, kTable, 1);  // a 1 cm thin table top
  const auto gt = gt_objects_from_points(cloud);
  // kGridPhase puts a z border at (k - 0.4127) * 2 cm; move the top to 1 mm under one, the
  // map 3 mm higher.
  const float border = (21 - 0.4127f) * 0.02f, shift = border - 0.001f - gt[0].points.front().z();
  auto truth = gt, map = gt;
  for (auto& p : truth[0].points) p.z() += shift;
  for (auto& p : map[0].points) p.z() += shift + 0.003f;
  const ObjectEvaluation e = evaluate_objects(truth, map);
  EXPECT_DOUBLE_EQ(e.wov, 1.0);
  EXPECT_LT(e.wov_voxel, 0.8);
}

// Map points beyond the match distance of the object count against precision; unmapped parts
// of the object against recall.
TEST(ObjectMetrics, StrayPointsCostPrecisionAndMissingPartsRecall) {
  const auto gt = gt_objects_from_points(make_gt_points());
  EvalObject stray = gt[2];
  for (const auto& p : gt[2].points) stray.points.push_back(p + Eigen::Vector3f(0.0f, 0.0f, 1.0f));
  stray.points.push_back(Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN()));
  const ObjectEvaluation e = evaluate_objects({gt[2]}, {stray});
  const double n = static_cast<double>(gt[2].points.size());
  // A copy 1 m above the table and one non-finite point: n of 2n + 1 points are on it.
  EXPECT_NEAR(e.per_gt[0].best_precision, n / (2 * n + 1), 1e-12);
  EXPECT_DOUBLE_EQ(e.per_gt[0].best_recall, 1.0);
  EXPECT_NEAR(e.per_gt[0].best_iou, e.per_gt[0].best_precision, 1e-12);

  ObjectEvalOptions strict;
  strict.match_distance_m = 0.005;  // the 1 cm sampling of a shifted copy is > 5 mm away
  EvalObject shifted = gt[2];
  for (auto& p : shifted.points) p += Eigen::Vector3f(0.005f, 0.005f, 0.0f);
  EXPECT_LT(evaluate_objects({gt[2]}, {shifted}, strict).wov, 0.5);
  EXPECT_DOUBLE_EQ(evaluate_objects({gt[2]}, {shifted}).wov, 1.0);
  strict.match_distance_m = 0.0;
  EXPECT_THROW(evaluate_objects({gt[2]}, {shifted}, strict), Error);
}

TEST(ObjectMetrics, DroppedObject) {
  const auto gt = gt_objects_from_points(make_gt_points());
  auto map = gt;
  map.erase(map.begin() + 2);  // the table
  const ObjectEvaluation e = evaluate_objects(gt, map);
  EXPECT_NEAR(e.wov, expected_wov_without(e, 3), 1e-12);
  EXPECT_LT(e.wov, 0.7);
  for (const auto& m : e.matches) {
    EXPECT_EQ(m.true_positives, 3u);
    EXPECT_DOUBLE_EQ(m.precision, 1.0);
    EXPECT_DOUBLE_EQ(m.recall, 0.75);
  }
  for (const auto& c : e.counts)
    if (c.class_id == kTable) EXPECT_EQ(c.map, 0u);
}

TEST(ObjectMetrics, MergedNeighbours) {
  const auto gt = gt_objects_from_points(make_gt_points());
  std::vector<EvalObject> map{gt[0], gt[2], gt[3]};
  map[0].points.insert(map[0].points.end(), gt[1].points.begin(), gt[1].points.end());  // chairs merged
  const ObjectEvaluation e = evaluate_objects(gt, map);
  const double g1 = static_cast<double>(e.per_gt[0].voxels), g2 = static_cast<double>(e.per_gt[1].voxels);
  // Recall 1 for both chairs; precision = each chair's share of the merged points (10 cm apart).
  const double n1 = static_cast<double>(gt[0].points.size()), n2 = static_cast<double>(gt[1].points.size());
  const double iou1 = n1 / (n1 + n2), iou2 = n2 / (n1 + n2);
  EXPECT_NEAR(e.per_gt[0].best_iou, iou1, 1e-12);
  EXPECT_NEAR(e.per_gt[1].best_iou, iou2, 1e-12);
  EXPECT_DOUBLE_EQ(e.per_gt[1].best_recall, 1.0);
  EXPECT_NEAR(e.per_gt[1].best_precision, iou2, 1e-12);
  double total = 0;
  for (const auto& g : e.per_gt) total += static_cast<double>(g.voxels);
  EXPECT_NEAR(e.wov, (total - g1 - g2 + g1 * iou1 + g2 * iou2) / total, 1e-12);
  EXPECT_LT(e.wov, 0.95);
  // Bigger chair still matches at 0.25 and 0.5 (IoU ~0.6), the smaller one is lost.
  ASSERT_GT(iou1, 0.5);
  for (const auto& m : e.matches) {
    EXPECT_EQ(m.true_positives, 3u);
    EXPECT_DOUBLE_EQ(m.precision, 1.0);
    EXPECT_DOUBLE_EQ(m.recall, 0.75);
  }
  for (const auto& c : e.counts)
    if (c.class_id == kChair) {
      EXPECT_EQ(c.gt, 2u);
      EXPECT_EQ(c.map, 1u);
    }
}

TEST(ObjectMetrics, WrongClassCountsForWovButNotForMatches) {
  const auto gt = gt_objects_from_points(make_gt_points());
  auto map = gt;
  map[3].class_id = kChair;  // cup called a chair
  const ObjectEvaluation e = evaluate_objects(gt, map);
  EXPECT_DOUBLE_EQ(e.wov, 1.0);
  EXPECT_LT(e.wov_same_class, 1.0);
  EXPECT_EQ(e.matches[1].true_positives, 3u);
  EXPECT_DOUBLE_EQ(e.matches[1].precision, 0.75);
}

TEST(ObjectMetrics, PartialOverlapThresholds) {
  // A map object holding the lower ~40 % of the table's points: IoU in [0.25, 0.5).
  const auto gt = gt_objects_from_points(make_gt_points());
  EvalObject part = gt[2];
  part.points.clear();
  for (const auto& p : gt[2].points)
    if (p.x() < 2.45f + kGridOffset.x()) part.points.push_back(p);
  const ObjectEvaluation e = evaluate_objects({gt[2]}, {part});
  ASSERT_GT(e.per_gt[0].best_iou, 0.25);
  ASSERT_LT(e.per_gt[0].best_iou, 0.5);
  EXPECT_EQ(e.matches[0].true_positives, 1u);
  EXPECT_EQ(e.matches[1].true_positives, 0u);
}

TEST(ObjectMetrics, FilesSceneJsonAndPly) {
  test::TempDir dir("semap_eval_obj");
  const PointCloud gt_points = make_gt_points();
  write_ply(dir / "gt_points.ply", gt_points);
  const auto gt = gt_objects_from_points(gt_points);

  // objects.json written like src/objects does, from the GT instances.
  std::filesystem::create_directories(dir / "map" / "objects");
  nlohmann::json objects = nlohmann::json::array();
  for (const auto& o : gt) {
    PointCloud cloud;
    cloud.points = o.points;
    write_ply(dir / "map" / "objects" / (std::to_string(o.id + 10) + ".ply"), cloud);
    objects.push_back({{"id", o.id + 10}, {"class", std::string(class_name(o.class_id))},
                       {"class_id", o.class_id}, {"point_count", o.points.size()},
                       {"points_file", "objects/" + std::to_string(o.id + 10) + ".ply"}});
  }
  test::write_text(dir / "map" / "objects.json", nlohmann::json({{"objects", objects}}).dump());
  const ObjectEvaluation e = evaluate_object_files(dir / "gt_points.ply", dir / "map" / "objects.json");
  EXPECT_DOUBLE_EQ(e.wov, 1.0);
  EXPECT_EQ(e.per_gt[0].best_map_id, 11);

  // scene.json with the same boxes as OBBs: the shells match the sampled surfaces.
  nlohmann::json scene_objects = nlohmann::json::array();
  const std::vector<std::pair<Eigen::Vector3f, Eigen::Vector3f>> boxes{
      {{0.0f, 0.0f, 0.0f}, {0.5f, 0.5f, 0.9f}}, {{0.6f, 0.0f, 0.0f}, {1.0f, 0.4f, 0.8f}},
      {{2.0f, 0.0f, 0.0f}, {3.2f, 0.8f, 0.75f}}, {{2.2f, 0.2f, 0.80f}, {2.28f, 0.28f, 0.9f}}};
  for (size_t k = 0; k < boxes.size(); ++k) {
    const Eigen::Vector3f c = 0.5f * (boxes[k].first + boxes[k].second) + kGridOffset, ext = boxes[k].second - boxes[k].first;
    scene_objects.push_back({{"instance_id", k + 1}, {"class_id", gt[k].class_id},
                             {"obb", {{"center", {c.x(), c.y(), c.z()}}, {"extent", {ext.x(), ext.y(), ext.z()}},
                                      {"rotation", {1, 0, 0, 0, 1, 0, 0, 0, 1}}}}});
  }
  test::write_text(dir / "scene.json", nlohmann::json({{"objects", scene_objects}}).dump());
  const ObjectEvaluation s = evaluate_object_files(dir / "scene.json", dir / "map" / "objects.json");
  EXPECT_EQ(s.gt_objects, 4u);
  EXPECT_GT(s.wov, 0.8);  // voxel boundary effects only
  EXPECT_EQ(s.matches[1].true_positives, 4u);

  // Errors name the file.
  std::filesystem::remove(dir / "map" / "objects" / "13.ply");
  try {
    evaluate_object_files(dir / "gt_points.ply", dir / "map" / "objects.json");
    FAIL() << "no error";
  } catch (const Error& err) {
    EXPECT_NE(std::string(err.what()).find("13.ply"), std::string::npos) << err.what();
  }
  test::write_text(dir / "bad.json", "{\"objects\": [");
  EXPECT_THROW(evaluate_object_files(dir / "bad.json", dir / "map" / "objects.json"), Error);
  EXPECT_THROW(load_map_objects(dir / "bad.json"), Error);
  EXPECT_THROW(load_gt_objects(dir / "nothing.ply", 0.01), Error);
}

}  // namespace
}  // namespace semap
