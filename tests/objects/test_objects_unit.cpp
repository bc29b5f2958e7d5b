// Unit tests of METHODS.md C2.3-C2.5 (weights, convexity, planes, clustering) and C4-C5
// (association, deletion, merging, JS divergence).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "objects/frame_segmenter.hpp"
#include "objects/object_map.hpp"
#include "objects/object_mapper.hpp"
#include "objects/segment_graph.hpp"

using namespace semap;

TEST(ObjectsGraph, FelzenszwalbSeparatesTwoCliques) {
  // Two triangles of tight edges joined by one heavy edge.
  std::vector<WeightedEdge> edges = {{0, 1, 0.1f}, {1, 2, 0.1f}, {0, 2, 0.2f}, {3, 4, 0.1f},
                                     {4, 5, 0.1f}, {3, 5, 0.1f}, {2, 3, 3.0f}};
  const auto comp = felzenszwalb_cluster(6, edges, 2.f);
  EXPECT_EQ(comp[0], comp[1]);
  EXPECT_EQ(comp[1], comp[2]);
  EXPECT_EQ(comp[3], comp[4]);
  EXPECT_EQ(comp[4], comp[5]);
  EXPECT_NE(comp[0], comp[3]);
  // A huge K merges everything; K -> 0 merges only zero-weight edges.
  const auto one = felzenszwalb_cluster(6, edges, 100.f);
  for (int c : one) EXPECT_EQ(c, one[0]);
  const auto none = felzenszwalb_cluster(6, edges, 1e-6f);
  std::set<int> distinct(none.begin(), none.end());
  EXPECT_EQ(distinct.size(), 6u);
}

TEST(ObjectsGraph, FelzenszwalbRespectsInternalDifference) {
  // Singletons merge at weight 1.5 (K/1 = 2), but the 4-node chain (Int 1.5, K/4 = 0.5)
  // refuses a weight-2.5 edge to a new singleton... while accepting 1.9.
  std::vector<WeightedEdge> edges = {{0, 1, 1.5f}, {1, 2, 1.5f}, {2, 3, 1.5f}, {3, 4, 2.5f}, {0, 5, 1.9f}};
  const auto comp = felzenszwalb_cluster(6, edges, 2.f);
  EXPECT_EQ(comp[0], comp[3]);
  EXPECT_NE(comp[3], comp[4]);
  EXPECT_EQ(comp[0], comp[5]);
}

TEST(ObjectsGraph, SemanticWeightTable) {
  EXPECT_FLOAT_EQ(semantic_weight(3, 3, 3.f, 1.f), 0.f);
  EXPECT_FLOAT_EQ(semantic_weight(3, 4, 3.f, 1.f), 3.f);
  EXPECT_FLOAT_EQ(semantic_weight(0, 4, 3.f, 1.f), 1.f);
  EXPECT_FLOAT_EQ(semantic_weight(4, 0, 3.f, 1.f), 1.f);
  EXPECT_FLOAT_EQ(semantic_weight(0, 0, 3.f, 1.f), 1.f);
}

TEST(ObjectsGraph, GeometricWeightTable) {
  const Eigen::Vector3f up(0, 0, 1), tilted = Eigen::Vector3f(1, 0, 1).normalized();
  EXPECT_FLOAT_EQ(geometric_weight(2, 2, up, tilted, false), 0.f);
  EXPECT_FLOAT_EQ(geometric_weight(0, 0, up, tilted, false), 0.f);  // as printed in C2.4
  EXPECT_FLOAT_EQ(geometric_weight(0, 1, up, tilted, true), 1.f);
  EXPECT_FLOAT_EQ(geometric_weight(1, 0, up, tilted, false), 1.f);
  const float d = 1.f - up.dot(tilted);
  EXPECT_NEAR(geometric_weight(1, 2, up, tilted, true), 0.25f * d * d, 1e-6f);
  EXPECT_NEAR(geometric_weight(1, 2, up, tilted, false), d, 1e-6f);
  EXPECT_LT(geometric_weight(1, 2, up, tilted, true), geometric_weight(1, 2, up, tilted, false));
}

TEST(ObjectsGraph, ConvexityOfRidgeAndValley) {
  const Eigen::Vector3f ci(-0.5f, 0, 0), cj(0.5f, 0, 0);
  const Eigen::Vector3f ridge_i = Eigen::Vector3f(-1, 0, 1).normalized(), ridge_j = Eigen::Vector3f(1, 0, 1).normalized();
  EXPECT_TRUE(generally_convex(ci, ridge_i, cj, ridge_j));
  EXPECT_FALSE(generally_convex(ci, ridge_j, cj, ridge_i));  // valley
  // Sanity: d along n_i x n_j (a step seen edge-on) fails, d perpendicular passes.
  EXPECT_TRUE(passes_sanity_criterion(ci, ridge_i, cj, ridge_j, 60.f));
  const Eigen::Vector3f s = ridge_i.cross(ridge_j).normalized();
  EXPECT_FALSE(passes_sanity_criterion(Eigen::Vector3f::Zero(), ridge_i, s, ridge_j, 60.f));
}

TEST(ObjectsGraph, TrulyConvexNeedsCommonNeighbour) {
  // Roof ridge: 0 and 1 on the two roof faces, 2 on top of the ridge; all pairs convex.
  SupervoxelGraph g;
  g.nodes.resize(4);
  g.nodes[0].centroid = {-0.5f, 0, 0};
  g.nodes[0].normal = Eigen::Vector3f(-1, 0, 1).normalized();
  g.nodes[1].centroid = {0.5f, 0, 0};
  g.nodes[1].normal = Eigen::Vector3f(1, 0, 1).normalized();
  g.nodes[2].centroid = {0, 0.1f, 0.3f};
  g.nodes[2].normal = Eigen::Vector3f(0, 0, 1);
  g.nodes[3].centroid = {1.5f, 0, 0};
  g.nodes[3].normal = Eigen::Vector3f(0, 0, 1);
  g.edges = {{0, 1}, {0, 2}, {1, 2}, {1, 3}};
  const auto convex = truly_convex_edges(g, 60.f);
  EXPECT_TRUE(convex[0]);   // 0-1 has the common convex neighbour 2
  EXPECT_FALSE(convex[3]);  // 1-3 has no common neighbour
}

TEST(ObjectsGraph, SupportPlaneRegionGrowing) {
  // A 6x6 grid of flat supervoxels on z = 0 plus a curved blob on top: one plane.
  SupervoxelGraph g;
  for (int y = 0; y < 6; ++y)
    for (int x = 0; x < 6; ++x) {
      SupervoxelNode n;
      n.centroid = {x * 0.1f, y * 0.1f, 0.f};
      n.normal = {0, 0, 1};
      n.curvature = 0.001f;
      g.nodes.push_back(n);
    }
  for (int y = 0; y < 6; ++y)
    for (int x = 0; x < 6; ++x) {
      if (x + 1 < 6) g.edges.emplace_back(y * 6 + x, y * 6 + x + 1);
      if (y + 1 < 6) g.edges.emplace_back(y * 6 + x, (y + 1) * 6 + x);
    }
  SupervoxelNode blob;
  blob.centroid = {0.25f, 0.25f, 0.1f};
  blob.normal = Eigen::Vector3f(1, 0, 1).normalized();
  blob.curvature = 0.2f;
  g.nodes.push_back(blob);
  g.edges.emplace_back(14, 36);
  const auto planes = assign_support_planes(g, SupportPlaneParams{});
  for (int i = 0; i < 36; ++i) EXPECT_EQ(planes[i], 1);
  EXPECT_EQ(planes[36], 0);
}

TEST(ObjectsScores, JensenShannonValues) {
  EXPECT_NEAR(js_divergence({0.5, 0.5}, {0.5, 0.5}), 0.0, 1e-12);
  EXPECT_NEAR(js_divergence({1.0, 0.0}, {0.0, 1.0}), std::log(2.0), 1e-12);
  // p = (1, 0), q = (0.5, 0.5): m = (0.75, 0.25);
  // JS = 0.5 ln(1/0.75) + 0.5 (0.5 ln(0.5/0.75) + 0.5 ln(0.5/0.25)).
  const double expected = 0.5 * std::log(1 / 0.75) + 0.5 * (0.5 * std::log(0.5 / 0.75) + 0.5 * std::log(2.0));
  EXPECT_NEAR(js_divergence({1.0, 0.0}, {0.5, 0.5}), expected, 1e-12);
  const auto aug = augmented_mean_scores({0.0, 1.2, 0.4}, 2);  // n = 2: means 0.6, 0.2
  ASSERT_EQ(aug.size(), 4u);
  EXPECT_NEAR(aug[0], 0.2, 1e-12);
  EXPECT_NEAR(aug[2], 0.6, 1e-12);
  EXPECT_NEAR(aug[3], 0.2, 1e-12);
}

namespace {

/// `s` with grey colours and class `cls` at full confidence.
ObjectSegment certain_segment(ObjectSegment s, ClassId cls) {
  s.colours.assign(s.points.size(), Rgb8{});
  s.class_id = cls;
  s.score = 1.f;
  s.class_scores.assign(kNumClasses, 0.0);
  s.class_scores[cls] = 1.0;
  return s;
}

ObjectSegment cube_segment(const Eigen::Vector3f& corner, float size, ClassId cls, float step = 0.01f) {
  ObjectSegment s;
  for (float x = 0; x < size; x += step)
    for (float y = 0; y < size; y += step)
      for (float z = 0; z < size; z += step)
        if (x == 0 || y == 0 || z == 0 || x + step >= size || y + step >= size || z + step >= size)
          s.points.push_back(corner + Eigen::Vector3f(x, y, z));
  return certain_segment(std::move(s), cls);
}
ObjectsConfig toy_config() {
  ObjectsConfig c;
  c.optimise_every = 50;
  return c;
}
}  // namespace

TEST(ObjectsMap, AssociationMergesOrCreates) {
  ObjectsConfig c = toy_config();
  c.association_gate = AssociationGate::centroid;  // C4 as printed
  ObjectMap map(c);
  const ClassId cup = id(Label::kCup);
  map.associate({cube_segment({0, 0, 0}, 0.1f, cup)}, 0, 1);
  ASSERT_EQ(map.instances().size(), 1u);
  // Same cube shifted by 4 mm: overlap ~1 > 0.5 -> merged.
  map.associate({cube_segment({0.004f, 0, 0}, 0.1f, cup)}, 1, 2);
  ASSERT_EQ(map.instances().size(), 1u);
  EXPECT_EQ(map.instances()[0].n, 2);
  // A cube 0.3 m away: inside the 1 m gate but no overlap -> new instance, both counted.
  map.associate({cube_segment({0.3f, 0, 0}, 0.1f, cup)}, 2, 3);
  ASSERT_EQ(map.instances().size(), 2u);
  EXPECT_EQ(map.instances()[0].association_count, 3);
  // A cube 3 m away: outside the gate -> new instance, the first one not counted.
  map.associate({cube_segment({3.f, 0, 0}, 0.1f, cup)}, 3, 4);
  ASSERT_EQ(map.instances().size(), 3u);
  EXPECT_EQ(map.instances()[0].association_count, 3);
  // Voxel downsampling keeps memory bounded: repeated merging does not grow the point set.
  const size_t before = map.instances()[0].points.size();
  for (int i = 0; i < 5; ++i) map.associate({cube_segment({0, 0, 0}, 0.1f, cup)}, 5 + i, 5 + i);
  EXPECT_LE(map.instances()[0].points.size(), before + before / 10);
  // Co-candidacy counted for the pair (cube at 0 and cube at 0.3 m).
  const auto& first = map.instances()[0];
  EXPECT_GE(first.co_association.at(map.instances()[1].id), 1);
}

TEST(ObjectsMap, ExtendAddsPointsButNeverCreatesOrCounts) {
  ObjectMap map(toy_config());
  const ClassId cup = id(Label::kCup);
  EXPECT_EQ(map.extend({cube_segment({0, 0, 0}, 0.1f, cup)}, 0), 0u);  // empty map: nothing created
  EXPECT_TRUE(map.instances().empty());
  map.associate({cube_segment({0, 0, 0}, 0.1f, cup)}, 0, 1);
  const ObjectInstance before = map.instances()[0];
  // The same cube grown by 1 cm: overlap > r, its new surface joins; n, c and s stay (C5 sees keyframes only).
  EXPECT_EQ(map.extend({cube_segment({0, 0, 0}, 0.11f, cup)}, 7), 1u);
  ASSERT_EQ(map.instances().size(), 1u);
  const auto& after = map.instances()[0];
  EXPECT_GT(after.points.size(), before.points.size());
  EXPECT_EQ(after.n, before.n);
  EXPECT_EQ(after.association_count, before.association_count);
  EXPECT_EQ(after.score_sum, before.score_sum);
  EXPECT_EQ(after.last_frame, 7u);
  // Another class, or no overlap: dropped, never a new instance.
  EXPECT_EQ(map.extend({cube_segment({0, 0, 0}, 0.1f, id(Label::kBottle))}, 8), 0u);
  EXPECT_EQ(map.extend({cube_segment({0.3f, 0, 0}, 0.1f, cup)}, 9), 0u);
  EXPECT_EQ(map.instances().size(), 1u);
}

// After a loop closure each point moves with the frame it was observed in: a cup mapped from
// frame 0 (pose unchanged) and grown from frame 7 (pose corrected by 5 cm) ends up with frame 7's
// points shifted and frame 0's in place.
TEST(ObjectsMap, PoseCorrectionsMovePointsOfTheirFrames) {
  ObjectMap map(toy_config());
  const ClassId cup = id(Label::kCup);
  map.associate({cube_segment({0, 0, 0}, 0.1f, cup)}, 0, 1);
  map.extend({cube_segment({0, 0, 0}, 0.11f, cup)}, 7);
  const ObjectInstance before = map.instances()[0];
  ASSERT_EQ(before.point_frames.size(), before.points.size());
  const Eigen::Isometry3f shift(Eigen::Translation3f(0.05f, 0, 0));
  map.apply_pose_corrections({{7u, shift}});
  const ObjectInstance& after = map.instances()[0];
  size_t moved = 0, kept = 0;
  for (size_t i = 0; i < after.points.size(); ++i) {
    const Eigen::Vector3f& p = after.points[i];
    bool found = false;
    for (size_t j = 0; j < before.points.size() && !found; ++j) {
      const Eigen::Vector3f expected = before.point_frames[j] == 7u ? shift * before.points[j] : before.points[j];
      found = (expected - p).norm() < 1e-6f;
      if (found) (before.point_frames[j] == 7u ? moved : kept) += 1;
    }
    EXPECT_TRUE(found) << i;
  }
  EXPECT_GT(moved, 0u);
  EXPECT_GT(kept, 0u);
  EXPECT_NEAR((after.centroid() - before.centroid()).x(), 0.05f * moved / after.points.size(), 0.01f);
}

TEST(ObjectsMap, DeletionRule) {
  ObjectsConfig c = toy_config();  // T = 50: delete when s + n < 5 and unseen for > 10 steps
  ObjectMap map(c);
  const ClassId cup = id(Label::kCup), chair = id(Label::kChair);
  for (int i = 0; i < 8; ++i) map.associate({cube_segment({0, 0, 0}, 0.1f, cup)}, i, i + 1);  // s = 8, n = 8
  map.associate({cube_segment({2, 0, 0}, 0.1f, chair)}, 8, 9);    // s = 1, n = 1, old
  map.associate({cube_segment({5, 0, 0}, 0.1f, chair)}, 45, 45);  // s = 1, n = 1, recent
  const auto stats = map.optimise(50, false);
  EXPECT_EQ(stats.deleted, 1);
  ASSERT_EQ(map.instances().size(), 2u);
  EXPECT_EQ(map.instances()[0].state, InstanceState::kStable);
  EXPECT_EQ(map.instances()[1].state, InstanceState::kUnstable);
  EXPECT_EQ(map.instances()[0].association_count, 0);  // reset after optimisation
  // Final pass ignores recency: the recent rare one goes.
  map.optimise(60, true);
  EXPECT_EQ(map.instances().size(), 1u);
}

TEST(ObjectsMap, DeletedFragmentOfStableInstanceKeepsItsSurface) {
  ObjectsConfig c = toy_config();
  c.overlap_ratio = 0.95;  // the glimpse below does not associate (C4)
  c.reverse_containment = false;
  const ClassId sofa = id(Label::kSofa), cup = id(Label::kCup);
  ObjectMap map(c);
  for (int i = 0; i < 8; ++i) map.associate({cube_segment({0, 0, 0}, 0.2f, sofa)}, i, i + 1);
  // A rare glimpse half on the sofa, half new surface; and a rare cup far from it.
  map.associate({cube_segment({0.1f, 0, 0}, 0.2f, sofa)}, 8, 9);
  map.associate({cube_segment({0.6f, 0, 0}, 0.1f, cup)}, 9, 10);
  ASSERT_EQ(map.instances().size(), 3u);
  const size_t before = map.instances()[0].points.size();
  const auto stats = map.optimise(50, false);
  EXPECT_EQ(stats.deleted, 2);
  EXPECT_EQ(stats.absorbed, 1);  // the glimpse's surface joins the sofa, the cup's does not
  ASSERT_EQ(map.instances().size(), 1u);
  EXPECT_GT(map.instances()[0].points.size(), before);
  EXPECT_EQ(map.instances()[0].n, 8);  // counts are not merged
  Eigen::Vector3f hi = Eigen::Vector3f::Constant(-1e9f);
  for (const auto& p : map.instances()[0].points) hi = hi.cwiseMax(p);
  EXPECT_NEAR(hi.x(), 0.29f, 0.011f);
  EXPECT_LT(hi.x(), 0.5f);

  // Switched off: the glimpse is simply deleted.
  c.absorb_fragments = false;
  ObjectMap plain(c);
  for (int i = 0; i < 8; ++i) plain.associate({cube_segment({0, 0, 0}, 0.2f, sofa)}, i, i + 1);
  plain.associate({cube_segment({0.1f, 0, 0}, 0.2f, sofa)}, 8, 9);
  EXPECT_EQ(plain.optimise(50, false).absorbed, 0);
  EXPECT_EQ(plain.instances()[0].points.size(), before);
}

TEST(ObjectsMap, MergeRuleNeedsCoAssociationOverlapAndSimilarLabels) {
  ObjectsConfig c = toy_config();
  c.overlap_ratio = 0.95;  // force duplicates: partial views do not associate
  c.reverse_containment = false;
  const ClassId cup = id(Label::kCup), bowl = id(Label::kBowl);
  auto run = [&](ClassId second_class) {
    ObjectMap map(c);
    // Two duplicate instances of one 20 cm box: A is the full box, B its left 60 %; seen together.
    for (int i = 0; i < 6; ++i) {
      ObjectSegment full = cube_segment({0, 0, 0}, 0.2f, cup);
      ObjectSegment part = cube_segment({0, 0, 0}, 0.2f, second_class);
      std::vector<Eigen::Vector3f> kept;
      for (const auto& p : part.points)
        if (p.x() < 0.12f) kept.push_back(p);
      part.points = kept;
      part.colours.assign(kept.size(), Rgb8{});
      map.associate({part}, i, i + 1);  // part first, so the full view does not fold into it
      map.associate({full}, i, i + 1);
    }
    return map;
  };
  {
    ObjectMap map = run(cup);
    ASSERT_EQ(map.instances().size(), 2u);  // duplicates before optimisation
    const auto stats = map.optimise(50, false);
    EXPECT_EQ(stats.merged, 1);
    ASSERT_EQ(map.instances().size(), 1u);
    EXPECT_EQ(map.instances()[0].n, 12);
  }
  {
    ObjectMap map = run(bowl);  // different labels: JS = ln 2 > threshold -> kept apart
    ASSERT_EQ(map.instances().size(), 2u);
    const auto stats = map.optimise(50, false);
    EXPECT_EQ(stats.merged, 0);
    EXPECT_EQ(map.instances().size(), 2u);
  }
  {
    // Far apart (no overlap) with the same label -> kept apart.
    ObjectMap map(c);
    for (int i = 0; i < 6; ++i)
      map.associate({cube_segment({0, 0, 0}, 0.2f, cup), cube_segment({0.5f, 0, 0}, 0.2f, cup)}, i, i + 1);
    ASSERT_EQ(map.instances().size(), 2u);
    EXPECT_EQ(map.optimise(50, false).merged, 0);
  }
}

// Exported boxes describe the object's body: a separate cluster of points that bled in across a
// depth edge (here a wall patch 1 m away) and a few stray points do not stretch them.
TEST(ObjectsBoxes, LargestClusterAndTrimmedExtents) {
  std::vector<Eigen::Vector3f> points;
  for (float x = 0; x <= 0.6f; x += 0.01f)
    for (float y = 0; y <= 0.4f; y += 0.01f) points.emplace_back(x, y, 0.75f);  // table top 0.6 x 0.4
  for (float y = 0; y <= 0.3f; y += 0.01f)
    for (float z = 0; z <= 0.3f; z += 0.01f) points.emplace_back(1.6f, y, z);  // wall patch, 1 m off
  const auto body = largest_cluster(points, 0.05);
  EXPECT_EQ(body.size(), 61u * 41u);
  for (const auto& p : body) EXPECT_FLOAT_EQ(p.z(), 0.75f);
  EXPECT_EQ(largest_cluster(points, 0.0).size(), points.size());  // 0: all points

  std::vector<Eigen::Vector3f> with_strays = body;
  for (int k = 0; k < 5; ++k) with_strays.emplace_back(0.3f, 0.2f, 0.75f - 0.4f * static_cast<float>(k + 1));
  const OrientedBox exact = fit_oriented_box(with_strays), trimmed = fit_oriented_box(with_strays, 0.01);
  const Eigen::Vector3f e = trimmed.extent;
  EXPECT_GT(exact.extent.maxCoeff(), 1.9f);  // the strays reach 2 m below the top
  EXPECT_NEAR(e.maxCoeff(), 0.6f, 0.03f);
  EXPECT_LT(e.minCoeff(), 0.01f);  // a flat top
}

TEST(ObjectsMap, InstanceIdsForPoints) {
  ObjectMap map(toy_config());
  map.associate({cube_segment({0, 0, 0}, 0.1f, id(Label::kCup)), cube_segment({1, 0, 0}, 0.1f, id(Label::kBowl))}, 0, 1);
  const auto ids = map.instance_ids_for({{0.05f, 0.05f, 0.0f}, {1.05f, 0.0f, 0.05f}, {0.5f, 0.5f, 0.5f}}, 0.02f);
  EXPECT_EQ(ids[0], map.instances()[0].id);
  EXPECT_EQ(ids[1], map.instances()[1].id);
  EXPECT_EQ(ids[2], 0u);
}

namespace {
// A 64x48 depth image: a fronto-parallel plate at 1 m (or a plane tilted in depth from 1 to 2 m
// across the mask) with the mask spilling 4 px over its right edge onto a wall at 3 m.
struct GateScene {
  Frame frame;
  SegmentationResult seg;
  CameraModel camera;
};
GateScene gate_scene(bool tilted) {
  GateScene s;
  s.camera.depth = {50.0, 50.0, 32.0, 24.0, 64, 48};
  s.frame.depth = cv::Mat(48, 64, CV_32FC1, cv::Scalar(3.f));
  for (int v = 10; v < 38; ++v)
    for (int u = 10; u < 40; ++u) s.frame.depth.at<float>(v, u) = tilted ? 1.f + (u - 10) / 29.f : 1.f + 0.002f * (u % 3);
  InstanceDetection det;
  det.id = 1;
  det.class_id = id(Label::kTable);
  det.score = 1.f;
  det.mask = cv::Mat::zeros(48, 64, CV_8UC1);
  det.mask(cv::Rect(10, 10, 34, 28)).setTo(255);  // 4 px of wall on the right
  det.box = cv::Rect(10, 10, 34, 28);
  s.seg.instances.push_back(det);
  return s;
}
float max_camera_depth(const std::vector<ObjectSegment>& segments) {
  float z = 0.f;
  for (const auto& seg : segments)
    for (const auto& p : seg.points) z = std::max(z, p.z());  // identity pose: world = camera
  return z;
}
}  // namespace

TEST(ObjectsSegmenter, MaskDepthGateDropsSurfaceBehindTheObject) {
  for (const SegmentationMode mode : {SegmentationMode::backprojection, SegmentationMode::supervoxel}) {
    SCOPED_TRACE(std::string(enum_name(kSegmentationModeNames, mode)));
    ObjectsConfig c;
    c.segmentation_mode = mode;
    c.pixel_stride = 1;
    c.min_segment_points = 10;
    c.mask_depth_gate_k = 3.0;
    GateScene s = gate_scene(false);
    const auto gated = FrameSegmenter(c, s.camera).segment(s.frame, s.seg, Pose::Identity());
    ASSERT_EQ(gated.size(), 1u);
    EXPECT_LT(max_camera_depth(gated), 1.1f);
    EXPECT_GE(gated[0].points.size(), 30u * 28u * 9 / 10);  // the plate itself stays
    c.mask_depth_gate_k = 0.0;  // off: the wall strip joins the object
    const auto plain = FrameSegmenter(c, s.camera).segment(s.frame, s.seg, Pose::Identity());
    ASSERT_EQ(plain.size(), 1u);
    if (mode == SegmentationMode::backprojection) EXPECT_GT(max_camera_depth(plain), 2.9f);
  }
  // A surface spanning 1-2 m in depth inside its own mask is kept whole (MAD scales the gate).
  ObjectsConfig c;
  c.segmentation_mode = SegmentationMode::backprojection;
  c.pixel_stride = 1;
  c.mask_depth_gate_k = 3.0;
  GateScene s = gate_scene(true);
  const auto tilted = FrameSegmenter(c, s.camera).segment(s.frame, s.seg, Pose::Identity());
  ASSERT_EQ(tilted.size(), 1u);
  EXPECT_EQ(tilted[0].points.size(), 30u * 28u);
  EXPECT_NEAR(max_camera_depth(tilted), 2.0f, 1e-3f);
}

// C3 class by evidence: the argmax class needs class_min_share of the summed scores, else the
// object is `other`; the detector's uncertainty (low scores) is no evidence for another class.
TEST(ObjectsMap, ClassIsDecidedByEvidenceWithOtherWhenUndecided) {
  std::vector<double> scores(kNumClasses, 0.0);
  EXPECT_EQ(evidence_class(scores, 0.5), 0);  // no evidence
  scores[id(Label::kTable)] = 0.9;             // three weak table views (0.3 each)
  EXPECT_EQ(evidence_class(scores, 0.5), id(Label::kTable));
  scores[id(Label::kOther)] = 1.2;  // and four views of a class outside the set
  EXPECT_EQ(evidence_class(scores, 0.5), id(Label::kOther));
  scores[id(Label::kOther)] = 0.0;
  scores[id(Label::kDesk)] = 0.8;  // table 0.53 / desk 0.47: undecided at 0.6
  EXPECT_EQ(evidence_class(scores, 0.5), id(Label::kTable));
  EXPECT_EQ(evidence_class(scores, 0.6), id(Label::kOther));
  const auto shares = evidence_shares(scores);
  EXPECT_NEAR(shares[id(Label::kTable)] + shares[id(Label::kDesk)], 1.0, 1e-12);

  // The instance's class follows its evidence as segments arrive (any class may merge here).
  ObjectsConfig c = toy_config();
  c.association_class_share = 0.0;
  ObjectMap map(c);
  const ClassId table = id(Label::kTable), other = id(Label::kOther);
  map.associate({cube_segment({0, 0, 0}, 0.2f, table)}, 0, 1);
  EXPECT_EQ(map.instances()[0].class_id(), table);
  for (int i = 0; i < 2; ++i) map.associate({cube_segment({0, 0, 0}, 0.2f, other)}, 1 + i, 2 + i);
  ASSERT_EQ(map.instances().size(), 1u);
  EXPECT_EQ(map.instances()[0].class_id(), other);
}

// C4 with the instance's extent: a 1.6 m table first seen at one end, then at the other end. The
// second view's centroid is more than association_distance from the instance's, but it overlaps
// the instance's surface: it must join it, not start a second table.
TEST(ObjectsMap, AssociationUsesTheInstanceExtent) {
  auto slab = [](float x0, float x1) {
    ObjectSegment s;
    for (float x = x0; x < x1; x += 0.01f)
      for (float y = 0; y < 0.8f; y += 0.01f) s.points.emplace_back(x, y, 0.75f);
    s.colours.assign(s.points.size(), Rgb8{});
    s.class_id = id(Label::kTable);
    s.score = 1.f;
    s.class_scores.assign(kNumClasses, 0.0);
    s.class_scores[s.class_id] = 1.0;
    return s;
  };
  for (const AssociationGate gate : {AssociationGate::extent, AssociationGate::centroid}) {
    ObjectsConfig c = toy_config();
    c.association_distance = 0.5;
    c.association_gate = gate;
    ObjectMap map(c);
    map.associate({slab(0.0f, 1.2f)}, 0, 1);   // centroid x 0.6
    map.associate({slab(0.75f, 1.6f)}, 1, 2);  // centroid x 1.18 (0.58 m off); 56 % on the first
    SCOPED_TRACE(std::string(enum_name(kAssociationGateNames, gate)));
    EXPECT_EQ(map.instances().size(), gate == AssociationGate::extent ? 1u : 2u);  // centroid gate: a duplicate
  }
  // The extent gate counts the instances a segment touches, not every one within 1 m: a cup
  // 0.3 m from another is not its candidate, so its association count says how often it was seen.
  ObjectMap map(toy_config());
  const ClassId cup = id(Label::kCup);
  map.associate({cube_segment({0, 0, 0}, 0.1f, cup)}, 0, 1);
  map.associate({cube_segment({0.3f, 0, 0}, 0.1f, cup)}, 1, 2);
  map.associate({cube_segment({0.3f, 0, 0}, 0.1f, cup)}, 2, 3);
  ASSERT_EQ(map.instances().size(), 2u);
  EXPECT_EQ(map.instances()[0].association_count, 1);
  EXPECT_EQ(map.instances()[1].association_count, 2);
  EXPECT_TRUE(map.instances()[0].co_association.empty());
}

// Extension to C4 (association_class_share): a mug whose mask bleeds onto the table overlaps the
// table's surface more than r, but the table's evidence has no cup in it: a new instance.
TEST(ObjectsMap, SegmentMergesOnlyIntoAnInstanceWithEvidenceForItsClass) {
  for (const double share : {0.2, 0.0}) {
    ObjectsConfig c = toy_config();
    c.association_class_share = share;
    c.reverse_containment = false;
    ObjectMap map(c);
    map.associate({cube_segment({0, 0, 0}, 0.3f, id(Label::kTable))}, 0, 1);
    map.associate({cube_segment({0.02f, 0.02f, 0.02f}, 0.26f, id(Label::kCup))}, 1, 2);
    SCOPED_TRACE(share);
    EXPECT_EQ(map.instances().size(), share > 0 ? 2u : 1u);
  }
}

// C5 test (3) with the extent: two stable duplicates of one chair, one built from its front, one
// from its back (no shared surface). The smaller lies inside the larger's box: merged. The same
// back face 0.5 m away is another object.
// Two chairs side by side (touching at x = 0.45 m). A mask that bleeds over the border once left
// the second chair a stray cluster 10 cm above the first one's seat. Its raw box then held all of
// the first chair, and C5's containment test (3) merged the two; the body box (the largest
// cluster linked within merge_body_link_distance, trimmed) ignores the stray cluster.
TEST(ObjectsMap, StrayClusterOfATouchingNeighbourDoesNotMergeItByContainment) {
  auto chair_at = [](float x0) {
    ObjectSegment s;
    for (float x = x0; x < x0 + 0.45f; x += 0.01f)
      for (float y = 0; y < 0.45f; y += 0.01f) s.points.emplace_back(x, y, 0.45f);  // seat
    for (float x = x0; x < x0 + 0.45f; x += 0.01f)
      for (float z = 0.45f; z < 0.9f; z += 0.01f) s.points.emplace_back(x, 0.45f, z);  // back rest
    return certain_segment(std::move(s), id(Label::kChair));
  };
  for (const bool stray : {false, true}) {
    ObjectMap map(toy_config());
    for (int i = 0; i < 6; ++i) {
      ObjectSegment second = chair_at(0.46f);
      if (stray && i == 2)
        for (float x = 0.1f; x < 0.2f; x += 0.01f)
          for (float y = 0.1f; y < 0.2f; y += 0.01f) second.points.emplace_back(x, y, 0.55f);
      map.associate({chair_at(0.0f), certain_segment(std::move(second), id(Label::kChair))}, i, i + 1);
    }
    ASSERT_EQ(map.instances().size(), 2u);
    SCOPED_TRACE(stray);
    if (stray) {  // the raw box of the second chair holds the first one
      const auto& [first, second] = std::tie(map.instances()[0], map.instances()[1]);
      EXPECT_TRUE(second.bounds.contains(first.centroid()));
    }
    const auto stats = map.optimise(50, false);
    EXPECT_EQ(stats.pairs_checked, 1);  // (1) and (2) hold: touching boxes make them co-candidates
    EXPECT_EQ(stats.merged, 0);
    EXPECT_EQ(stats.after_merge, 2u);
  }
}

TEST(ObjectsMap, MergeOfViewsFromOppositeSidesByContainment) {
  auto face = [](float x, float z0, float z1, ClassId cls) {
    ObjectSegment s;
    for (float y = 0; y < 0.4f; y += 0.01f)
      for (float z = z0; z < z1; z += 0.01f) s.points.emplace_back(x, y, z);
    for (float xx = 0; xx < 0.4f; xx += 0.01f)
      for (float y = 0; y < 0.4f; y += 0.01f) s.points.emplace_back(xx, y, 0.45f);  // seat
    return certain_segment(std::move(s), cls);
  };
  const ClassId chair = id(Label::kChair);
  for (const double ratio : {0.5, 1.0}) {
    ObjectsConfig c = toy_config();
    c.overlap_ratio = 0.95;  // the two views do not associate (C4)
    c.reverse_containment = false;
    c.merge_overlap_ratio = 0.9;  // nor pass the surface-overlap test
    c.merge_containment_ratio = ratio;
    ObjectMap map(c);
    for (int i = 0; i < 6; ++i) {
      ObjectSegment front = face(0.0f, 0.0f, 0.9f, chair);  // back rest and seat seen from the front
      ObjectSegment back = face(0.39f, 0.0f, 0.45f, chair);  // legs side seen from behind, inside
      for (auto& p : back.points) p.z() -= 0.02f;             // the seat 2 cm lower: no shared surface
      map.associate({front}, i, i + 1);
      map.associate({back}, i, i + 1);
    }
    ASSERT_EQ(map.instances().size(), 2u);
    const auto stats = map.optimise(50, false);
    EXPECT_EQ(stats.before, 2u);
    EXPECT_EQ(stats.after_delete, 2u);
    SCOPED_TRACE(ratio);
    EXPECT_EQ(stats.merged, ratio < 1.0 ? 1 : 0);
    EXPECT_EQ(stats.after_merge, ratio < 1.0 ? 1u : 2u);
  }
}

// Exported points the fused TSDF labels as another class (a cup a bleeding mask put in the
// table) are left out; unlabelled ones stay; when most disagree, the class is in doubt: all stay.
TEST(ObjectsExport, PointsOfOtherClassesAreLeftOutWhenAMinority) {
  const ClassId table = id(Label::kTable), cup = id(Label::kCup), floor = id(Label::kFloor);
  const std::vector<ClassId> bled{table, 0, cup, table, floor, table, 0};
  EXPECT_EQ(points_of_other_classes(bled, table), (std::vector<bool>{false, false, true, false, true, false, false}));
  const std::vector<ClassId> mostly_cup{cup, cup, cup, table, 0};
  EXPECT_EQ(points_of_other_classes(mostly_cup, table), std::vector<bool>(5, false));
  EXPECT_TRUE(points_of_other_classes({}, table).empty());
}
