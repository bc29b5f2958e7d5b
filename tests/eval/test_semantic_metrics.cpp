// Semantic mIoU / surface error / completeness on synthetic labelled point sets.
#include <gtest/gtest.h>

#include "semap/core/error.hpp"
#include "semap/eval/semantic_metrics.hpp"
#include "semap/io/ply_io.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

const ClassId kFloor = id(Label::kFloor), kTable = id(Label::kTable), kChair = id(Label::kChair);

// A 2 m x 2 m plane at z = 0 sampled every 1 cm; class by x band, an unlabelled strip at
// y >= 1.8 m.
PointCloud make_gt() {
  PointCloud cloud;
  for (int ix = 0; ix < 200; ++ix)
    for (int iy = 0; iy < 200; ++iy) {
      const float x = 0.01f * ix, y = 0.01f * iy;
      cloud.points.emplace_back(x, y, 0.0f);
      ClassId c = x < 0.5f ? kFloor : (x < 1.2f ? kTable : kChair);
      if (y >= 1.8f) c = 0;
      cloud.labels.push_back(c);
    }
  return cloud;
}

const ClassIoU* find_class(const SemanticEvaluation& e, ClassId c) {
  for (const auto& k : e.classes)
    if (k.class_id == c) return &k;
  return nullptr;
}

TEST(SemanticMetrics, PerfectCopy) {
  const PointCloud gt = make_gt();
  const SemanticEvaluation e = evaluate_semantic(gt, gt);
  ASSERT_EQ(e.classes.size(), 3u);  // unlabelled and absent classes excluded
  EXPECT_DOUBLE_EQ(e.miou, 1.0);
  EXPECT_DOUBLE_EQ(e.completeness, 1.0);
  EXPECT_LT(e.surface_error_mean_m, 1e-9);
  EXPECT_EQ(e.gt_points_missed, 0u);
}

TEST(SemanticMetrics, RelabelTenPercentOfOneClass) {
  const PointCloud gt = make_gt();
  PointCloud map = gt;
  size_t table_count = 0, relabelled = 0, chair_count = 0;
  for (size_t i = 0; i < map.size(); ++i) {
    if (gt.labels[i] == kChair) ++chair_count;
    if (gt.labels[i] != kTable) continue;
    if (table_count++ % 10 == 0) {
      map.labels[i] = kChair;
      ++relabelled;
    }
  }
  const SemanticEvaluation e = evaluate_semantic(gt, map);
  const double expected_table = static_cast<double>(table_count - relabelled) / table_count;
  const double expected_chair = static_cast<double>(chair_count) / (chair_count + relabelled);
  ASSERT_NE(find_class(e, kTable), nullptr);
  EXPECT_NEAR(find_class(e, kTable)->iou, expected_table, 1e-9);
  EXPECT_NEAR(find_class(e, kTable)->iou, 0.9, 0.002);
  EXPECT_NEAR(find_class(e, kChair)->iou, expected_chair, 1e-9);
  EXPECT_DOUBLE_EQ(find_class(e, kFloor)->iou, 1.0);
  EXPECT_NEAR(e.miou, (1.0 + expected_table + expected_chair) / 3.0, 1e-9);
}

TEST(SemanticMetrics, ShiftedByOneCentimetre) {
  const PointCloud gt = make_gt();
  PointCloud map = gt;
  for (auto& p : map.points) p.z() += 0.01f;
  const SemanticEvaluation e = evaluate_semantic(gt, map);
  EXPECT_NEAR(e.surface_error_mean_m, 0.01, 1e-4);
  EXPECT_NEAR(e.surface_error_median_m, 0.01, 1e-4);
  EXPECT_DOUBLE_EQ(e.completeness, 1.0);  // within 2 cm
  EXPECT_DOUBLE_EQ(e.miou, 1.0);          // labels still transfer within 5 cm
  SemanticEvalOptions tight;
  tight.completeness_distance_m = 0.005;
  EXPECT_DOUBLE_EQ(evaluate_semantic(gt, map, tight).completeness, 0.0);
}

TEST(SemanticMetrics, DensityOfTheMapDoesNotBiasIoU) {
  // A 3 cm-spaced map of the same labels: still perfect (both directions normalised).
  const PointCloud gt = make_gt();
  PointCloud map;
  for (size_t i = 0; i < gt.size(); ++i) {
    const int ix = static_cast<int>(i / 200), iy = static_cast<int>(i % 200);
    if (ix % 3 == 0 && iy % 3 == 0) map.push_back_from(gt, i);
  }
  const SemanticEvaluation e = evaluate_semantic(gt, map);
  // Band borders: GT points whose nearest map vertex lies across the border (<= 1 column).
  EXPECT_GT(e.miou, 0.97);
  EXPECT_DOUBLE_EQ(e.completeness, 1.0);
}

TEST(SemanticMetrics, MissingHalfAndOffSurfaceVertices) {
  const PointCloud gt = make_gt();
  PointCloud map;
  for (size_t i = 0; i < gt.size(); ++i)
    if (gt.points[i].x() < 1.0f) map.push_back_from(gt, i);  // no chair, half the table
  const SemanticEvaluation e = evaluate_semantic(gt, map);
  EXPECT_NEAR(e.completeness, 0.51, 0.006);  // half + the columns within 2 cm of the cut
  ASSERT_NE(find_class(e, kChair), nullptr);
  EXPECT_DOUBLE_EQ(find_class(e, kChair)->iou, 0.0);
  EXPECT_NEAR(find_class(e, kTable)->recall, (0.5 + 0.05) / 0.7, 0.03);  // band edges depend on float rounding
  EXPECT_DOUBLE_EQ(find_class(e, kTable)->precision, 1.0);

  // Floating vertices labelled floor 1 m above the plane: false positives of floor.
  PointCloud with_noise = map;
  const size_t n_noise = with_noise.size() / 4;
  for (size_t i = 0; i < n_noise; ++i) {
    with_noise.points.emplace_back(0.3f, 0.3f, 1.0f);
    with_noise.labels.push_back(kFloor);
  }
  const SemanticEvaluation noisy = evaluate_semantic(gt, with_noise);
  EXPECT_EQ(noisy.map_vertices_off_surface, n_noise);
  EXPECT_LT(find_class(noisy, kFloor)->precision, 0.75);
  EXPECT_LT(find_class(noisy, kFloor)->iou, 0.9);
  SemanticEvalOptions lenient;
  lenient.unmatched_map_vertices_are_false_positives = false;
  EXPECT_DOUBLE_EQ(find_class(evaluate_semantic(gt, with_noise, lenient), kFloor)->iou, 1.0);
  EXPECT_GT(noisy.surface_error_mean_m, 0.15);
}

TEST(SemanticMetrics, UnlabelledGroundTruthIsIgnored) {
  const PointCloud gt = make_gt();
  PointCloud map = gt;
  for (size_t i = 0; i < map.size(); ++i)
    if (gt.labels[i] == 0) map.labels[i] = kTable;  // any label on ignored GT costs nothing
  EXPECT_DOUBLE_EQ(evaluate_semantic(gt, map).miou, 1.0);
}

TEST(SemanticMetrics, UnlabelledMapGivesZero) {
  const PointCloud gt = make_gt();
  PointCloud map = gt;
  map.labels.clear();
  const SemanticEvaluation e = evaluate_semantic(gt, map);
  EXPECT_DOUBLE_EQ(e.miou, 0.0);
  EXPECT_EQ(e.classes.size(), 3u);
  EXPECT_DOUBLE_EQ(e.completeness, 1.0);
}

TEST(SemanticMetrics, FilesAndErrors) {
  test::TempDir dir("semap_eval_sem");
  const PointCloud gt = make_gt();
  write_ply(dir / "gt.ply", gt);
  const SemanticEvaluation e = evaluate_semantic_files(dir / "gt.ply", dir / "gt.ply");
  EXPECT_DOUBLE_EQ(e.miou, 1.0);
  try {
    evaluate_semantic_files(dir / "gt.ply", dir / "missing.ply");
    FAIL() << "no error";
  } catch (const Error& err) {
    EXPECT_NE(std::string(err.what()).find("missing.ply"), std::string::npos) << err.what();
  }
  PointCloud unlabelled = gt;
  unlabelled.labels.clear();
  write_ply(dir / "nolabels.ply", unlabelled);
  EXPECT_THROW(evaluate_semantic_files(dir / "nolabels.ply", dir / "gt.ply"), Error);
}

}  // namespace
}  // namespace semap
