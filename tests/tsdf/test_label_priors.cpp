// The geometry-aware label rules (tsdf/label_priors.hpp, issue 38) on a simulated room whose
// true classes are known: floor, two walls, a ceiling, a table top at 0.75 m and a cup on the
// table. The fused labels are corrupted the way a single-view network corrupts them: tiles of
// the table top called floor, tiles of the floor called table, cup labels on the wall, wall
// labels on the floor's edge tiles, and much left unlabelled. Each rule is measured on and off
// against the truth (share of the mesh area with the true class), and the floor thickness and
// normal agreement of eval/consistency_metrics.
#include <gtest/gtest.h>

#include <random>

#include "semap/eval/consistency_metrics.hpp"
#include "tsdf/label_priors.hpp"
#include "tsdf/voxel_label.hpp"

namespace semap {
namespace {

constexpr double kTile_m = 0.25;  // labels are corrupted in tiles of this size (network blobs)

struct World {
  TriangleMesh mesh;
  std::vector<ClassId> truth;  // per vertex
};

/// A grid of `nu` x `nv` cells of 5 cm spanning origin + [0, u] x [0, v]; normal u x v. Each
/// tile's observed label: the true one with p_true, `wrong` with p_wrong, else unlabelled.
void add_plane(World& w, const Eigen::Vector3f& origin, const Eigen::Vector3f& u, const Eigen::Vector3f& v,
               ClassId truth, ClassId wrong, double p_true, double p_wrong, std::mt19937& rng) {
  const int nu = static_cast<int>(std::lround(u.norm() / 0.05)), nv = static_cast<int>(std::lround(v.norm() / 0.05));
  const uint32_t base = static_cast<uint32_t>(w.mesh.vertices.points.size());
  const int tiles_u = static_cast<int>(std::ceil(u.norm() / kTile_m)) + 1;
  std::vector<ClassId> tile_label(static_cast<size_t>(tiles_u) * (static_cast<int>(v.norm() / kTile_m) + 2));
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  for (auto& l : tile_label) {
    const double r = uni(rng);
    l = r < p_true ? truth : r < p_true + p_wrong ? wrong : ClassId(0);
  }
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i <= nu; ++i) {
      const float a = float(i) / nu, b = float(j) / nv;
      w.mesh.vertices.points.push_back(origin + a * u + b * v);
      const int tu = static_cast<int>(a * u.norm() / kTile_m), tv = static_cast<int>(b * v.norm() / kTile_m);
      w.mesh.vertices.labels.push_back(tile_label[static_cast<size_t>(tv) * tiles_u + tu]);
      w.truth.push_back(truth);
    }
  const auto at = [&](int i, int j) { return base + static_cast<uint32_t>(j * (nu + 1) + i); };
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      w.mesh.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      w.mesh.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
}

/// The room; `with_floor` false: only the table, walls and ceiling are seen (no floor visible).
World room(bool with_floor, uint32_t seed = 7) {
  World w;
  std::mt19937 rng(seed);
  const ClassId floor = id(Label::kFloor), wall = id(Label::kWall), table = id(Label::kTable), cup = id(Label::kCup);
  using V = Eigen::Vector3f;
  if (with_floor) add_plane(w, V(0, 0, 0), V(4, 0, 0), V(0, 4, 0), floor, table, 0.55, 0.15, rng);  // faces up
  add_plane(w, V(0, 0, 0.3f), V(0, 0, 2.2f), V(4, 0, 0), wall, cup, 0.5, 0.15, rng);      // y = 0, faces +y
  add_plane(w, V(0, 0, 0.3f), V(0, 4, 0), V(0, 0, 2.2f), wall, floor, 0.5, 0.15, rng);    // x = 0, faces +x
  add_plane(w, V(0, 0, 2.6f), V(0, 4, 0), V(4, 0, 0), id(Label::kCeiling), wall, 0.3, 0.1, rng);  // faces down
  add_plane(w, V(1.5f, 1.5f, 0.75f), V(1.2f, 0, 0), V(0, 0.8f, 0), table, floor, 0.3, 0.5, rng);  // top, faces up
  // A cup (10 cm tall, vertical sides) on the table, labelled cup with wall blobs.
  for (int k = 0; k < 4; ++k) {
    const float a = float(k) * 1.5708f;
    const V o(2.0f + 0.05f * std::cos(a), 1.9f + 0.05f * std::sin(a), 0.75f);
    add_plane(w, o, V(0, 0, 0.1f), V(-0.07f * std::sin(a), 0.07f * std::cos(a), 0), cup, wall, 0.6, 0.2, rng);
  }
  return w;
}

GravityEstimate gravity(bool floor_found) {
  GravityEstimate g;
  g.up_W = Eigen::Vector3d::UnitZ();
  g.floor_found = floor_found;
  g.floor_height_m = 0.0;
  return g;
}

double vertex_accuracy(const World& w) {
  size_t ok = 0;
  for (size_t v = 0; v < w.truth.size(); ++v) ok += w.mesh.vertices.labels[v] == w.truth[v];
  return double(ok) / w.truth.size();
}

TsdfConfig rules(bool normals, bool heights, bool regions, bool segments = false, bool likely = false, bool other = false,
                 bool fringes = false) {
  TsdfConfig c;
  c.label_prior_normals = normals;
  c.label_prior_heights = heights;
  c.label_prior_regions = regions;
  c.label_prior_segments = segments;
  c.label_prior_likely = likely;
  c.label_prior_other = other;
  c.label_prior_fringes = fringes;
  return c;
}

struct Measured {
  double accuracy;
  SemanticConsistency consistency;
};
Measured run(bool with_floor, const TsdfConfig& c) {
  World w = room(with_floor);
  apply_label_priors(w.mesh, gravity(with_floor), c);
  return {vertex_accuracy(w), evaluate_consistency(w.mesh, {})};
}

TEST(LabelPriors, NormalRuleRemovesLabelsThatContradictTheSurface) {
  const Measured off = run(true, rules(false, false, false)), on = run(true, rules(true, false, false));
  // Wall labels on the (horizontal) ceiling, floor labels on the (vertical) wall go.
  EXPECT_LT(off.consistency.wall.agreement, 0.85);
  EXPECT_GT(on.consistency.wall.agreement, 0.97);
  EXPECT_GT(on.consistency.floor.facing_agreement, 0.97);
  EXPECT_LT(on.consistency.labelled_area_share, off.consistency.labelled_area_share);  // it only removes
}

TEST(LabelPriors, HeightRuleKeepsTheFloorOneSurface) {
  const Measured off = run(true, rules(true, false, false)), on = run(true, rules(true, true, false));
  ASSERT_TRUE(off.consistency.floor_thickness_m && on.consistency.floor_thickness_m);
  EXPECT_GT(*off.consistency.floor_thickness_m, 0.5);  // the table top called floor
  EXPECT_LT(*on.consistency.floor_thickness_m, 0.05);
}

TEST(LabelPriors, RegionsFillSurfacesWithTheirFittingClass) {
  const Measured classes = run(true, rules(true, true, false)), all = run(true, rules(true, true, true));
  const Measured none = run(true, rules(false, false, false));
  EXPECT_LT(none.accuracy, 0.6);
  EXPECT_GT(all.accuracy, 0.93);
  EXPECT_GT(all.accuracy, classes.accuracy + 0.2);
  EXPECT_GT(all.consistency.labelled_area_share, 0.97);
  EXPECT_GT(all.consistency.floor.facing_agreement, 0.97);
  EXPECT_GT(all.consistency.wall.agreement, 0.97);
  EXPECT_GT(all.consistency.ceiling.facing_agreement, 0.97);
  ASSERT_TRUE(all.consistency.floor_thickness_m);
  EXPECT_LT(*all.consistency.floor_thickness_m, 0.05);
}

TEST(LabelPriors, TheTableTopCalledFloorBecomesTable) {
  World w = room(true);
  apply_label_priors(w.mesh, gravity(true), rules(true, true, true));
  size_t top = 0, table = 0;
  for (size_t v = 0; v < w.truth.size(); ++v)
    if (w.truth[v] == id(Label::kTable)) {
      ++top;
      table += w.mesh.vertices.labels[v] == id(Label::kTable);
    }
  EXPECT_GT(double(table) / top, 0.95);
}

TEST(LabelPriors, WorkWithoutAVisibleFloor) {
  // Up is known (the cameras), the floor height is not: the normal and region rules still hold.
  const Measured none = run(false, rules(false, false, false)), all = run(false, rules(true, true, true));
  EXPECT_GT(all.accuracy, none.accuracy + 0.25);
  EXPECT_GT(all.consistency.wall.agreement, 0.97);
  EXPECT_GT(all.consistency.labelled_area_share, 0.9);
}

TEST(LabelPriors, AllRulesOffChangeNothing) {
  World w = room(true);
  const std::vector<ClassId> before = w.mesh.vertices.labels;
  const LabelPriorStats s = apply_label_priors(w.mesh, gravity(true), rules(false, false, false));
  EXPECT_EQ(w.mesh.vertices.labels, before);
  EXPECT_EQ(s.filled + s.replaced + s.contradicting + s.refitted, 0u);
}

/// One connected sheet at a TSDF mesh's spacing (2 cm), bent along a profile: the cross-section
/// points `profile` (metres, in the x-z plane) swept 0.6 m along y. Vertex k of the profile has
/// truth `truth[k]`; its observed label is drawn per 10 cm tile: the truth with p_seen, else
/// unlabelled.
World bent_sheet(const std::vector<Eigen::Vector2f>& profile, const std::vector<ClassId>& truth, double p_seen,
                 uint32_t seed) {
  World w;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const int ny = 30, tile = 5;
  std::vector<bool> seen(((profile.size() / tile) + 1) * (ny / tile + 1));
  for (size_t t = 0; t < seen.size(); ++t) seen[t] = uni(rng) < p_seen;
  for (size_t k = 0; k < profile.size(); ++k)
    for (int j = 0; j <= ny; ++j) {
      w.mesh.vertices.points.emplace_back(profile[k].x(), 0.02f * j, profile[k].y());
      w.truth.push_back(truth[k]);
      w.mesh.vertices.labels.push_back(seen[(k / tile) * (ny / tile + 1) + j / tile] ? truth[k] : ClassId(0));
    }
  const auto at = [&](size_t k, int j) { return static_cast<uint32_t>(k * (ny + 1) + j); };
  for (size_t k = 0; k + 1 < profile.size(); ++k)
    for (int j = 0; j < ny; ++j) {  // wound so that the normals face +z on a horizontal stretch
      w.mesh.triangles.push_back({at(k, j), at(k + 1, j), at(k + 1, j + 1)});
      w.mesh.triangles.push_back({at(k, j), at(k + 1, j + 1), at(k, j + 1)});
    }
  return w;
}

double share_of_truth(const World& w, ClassId truth, ClassId label) {
  size_t n = 0, hit = 0;
  for (size_t v = 0; v < w.truth.size(); ++v)
    if (w.truth[v] == truth) ++n, hit += w.mesh.vertices.labels[v] == label;
  return double(hit) / double(n);
}

TEST(LabelPriors, SegmentsFillASmoothSurfaceAndStopAtItsCrease) {
  // A sofa seat curving up into its back (one smooth surface: a quarter circle of 0.3 m), then a
  // crease into the top of a cabinet behind it. The network saw 40 % of the tiles of each.
  std::vector<Eigen::Vector2f> profile;
  std::vector<ClassId> truth;
  const auto add = [&](float x, float z, Label l) { profile.emplace_back(x, z), truth.push_back(id(l)); };
  for (int i = 25; i >= 0; --i) add(-0.02f * i, 0.45f, Label::kSofa);  // seat, faces up
  for (int i = 1; i <= 24; ++i) {
    const float a = 1.5708f * i / 24.f;
    add(0.3f * std::sin(a), 0.75f - 0.3f * std::cos(a), Label::kSofa);
  }
  for (int i = 1; i <= 15; ++i) add(0.3f, 0.75f + 0.02f * i, Label::kSofa);        // back, vertical
  for (int i = 1; i <= 30; ++i) add(0.3f + 0.02f * i, 1.05f, Label::kCabinet);    // crease: cabinet top
  World w = bent_sheet(profile, truth, 0.4, 11);
  const double seen_before = share_of_truth(w, id(Label::kSofa), id(Label::kSofa));
  const LabelPriorStats s = apply_label_priors(w.mesh, gravity(false), rules(true, true, false, true));
  EXPECT_LT(seen_before, 0.6);
  EXPECT_GT(share_of_truth(w, id(Label::kSofa), id(Label::kSofa)), 0.95);  // filled along the curve
  EXPECT_GT(share_of_truth(w, id(Label::kCabinet), id(Label::kCabinet)), 0.9);
  EXPECT_LT(share_of_truth(w, id(Label::kCabinet), id(Label::kSofa)), 0.05);  // not across the crease
  EXPECT_GT(s.segment_filled, 0u);
}

TEST(LabelPriors, SegmentsNeedEnoughLabelledAreaAndLeaveTheStructureToTheRegions) {
  // A sofa seat seen on 10 % of its tiles only: too little to decide.
  std::vector<Eigen::Vector2f> seat;
  for (int i = 0; i <= 60; ++i) seat.emplace_back(0.02f * i, 0.45f);
  World sparse = bent_sheet(seat, std::vector<ClassId>(seat.size(), id(Label::kSofa)), 0.1, 5);
  const double before = share_of_truth(sparse, id(Label::kSofa), id(Label::kSofa));
  apply_label_priors(sparse.mesh, gravity(true), rules(true, true, false, true));
  EXPECT_NEAR(share_of_truth(sparse, id(Label::kSofa), id(Label::kSofa)), before, 1e-9);
  // A counter front (vertical, 0.1-0.9 m) the network calls wall on 60 % of its tiles: the
  // segment never spreads wall (nor floor, nor ceiling); that is the planar regions' decision.
  std::vector<Eigen::Vector2f> front;
  for (int i = 0; i <= 40; ++i) front.emplace_back(0.0f, 0.9f - 0.02f * i);
  World counter = bent_sheet(front, std::vector<ClassId>(front.size(), id(Label::kWall)), 0.6, 9);
  const double walls_before = share_of_truth(counter, id(Label::kWall), id(Label::kWall));
  const LabelPriorStats s = apply_label_priors(counter.mesh, gravity(true), rules(true, true, false, true));
  EXPECT_LT(walls_before, 0.9);
  EXPECT_NEAR(share_of_truth(counter, id(Label::kWall), id(Label::kWall)), walls_before, 1e-9);
  EXPECT_EQ(s.segment_filled, 0u);
}

/// A counter top (horizontal, 0.9 m above the floor) and a wall beside it, both seen in ten
/// frames by a network that calls each wall six times and cabinet four, interleaved: the fused
/// evidence is the same on both and too split to show a label (wall leads by two frames' votes);
/// only the geometry tells them apart.
struct CounterAndWall {
  TsdfMap map{TsdfConfig{}};
  TriangleMesh mesh;
  size_t counter_vertices = 0;

  CounterAndWall() {
    World w;
    std::mt19937 rng(3);
    using V = Eigen::Vector3f;
    add_plane(w, V(0.51f, 0.51f, 0.91f), V(0.5f, 0, 0), V(0, 0.5f, 0), id(Label::kCabinet), 0, 1.0, 0.0, rng);
    counter_vertices = w.mesh.vertices.points.size();
    add_plane(w, V(0.51f, 0.01f, 0.31f), V(0, 0, 1.2f), V(0.5f, 0, 0), id(Label::kWall), 0, 1.0, 0.0, rng);
    mesh = std::move(w.mesh);
    std::vector<Label> votes;
    for (int frame = 0; frame < 10; ++frame) votes.push_back(frame % 5 < 3 ? Label::kWall : Label::kCabinet);
    for (size_t v = 0; v < mesh.vertices.points.size(); ++v) set_votes(v, votes);
    mesh.vertices.labels = surface_labels(map, mesh.vertices.points);
  }
  /// Replaces the fused evidence of the voxel under vertex v by these frames' votes, in order.
  void set_votes(size_t v, const std::vector<Label>& votes) {
    const VoxelIndex voxel = map.voxel_of_point(mesh.vertices.points[v]);
    Block& block = map.allocate_block(block_of_voxel(voxel));
    const int li = local_index(voxel);
    block.voxels[li].weight_q = 1;
    uint8_t* bayes = &block.bayes[static_cast<size_t>(li) * map.bayes().bytes_per_voxel()];
    std::fill_n(bayes, map.bayes().bytes_per_voxel(), 0);
    const float c = static_cast<float>(map.config().bayes_default_confidence);
    for (Label vote : votes)
      map.bayes().update(bayes, ClassDistribution::from_label(id(vote), c, map.config().bayes_confusion_classes));
  }
  double share(size_t from, size_t to, Label l) const {
    size_t n = 0;
    for (size_t v = from; v < to; ++v) n += mesh.vertices.labels[v] == id(l);
    return double(n) / double(to - from);
  }
};

TEST(LabelPriors, GeometryRulingAClassOutDecidesBetweenTheRest) {
  CounterAndWall without, with;
  const size_t counter = with.counter_vertices, all = with.mesh.vertices.points.size();
  ASSERT_GT(with.share(0, all, Label::kUnlabelled), 0.99);  // split evidence: nothing shown
  apply_label_priors(without.mesh, gravity(true), rules(true, true, false));
  const LabelPriorStats s =
      apply_label_priors(with.mesh, gravity(true), rules(true, true, false), SurfaceLabelEvidence(with.map, with.mesh.vertices.points));
  // On the counter wall is ruled out, and what remains is cabinet by four frames' votes.
  EXPECT_GT(with.share(0, counter, Label::kCabinet), 0.99);
  EXPECT_GT(without.share(0, counter, Label::kUnlabelled), 0.99);
  EXPECT_GE(s.refitted, counter);
  // On the wall, where both classes fit, the split evidence still shows nothing.
  EXPECT_GT(with.share(counter, all, Label::kUnlabelled), 0.99);
}

TEST(LabelPriors, EvidenceTooThinAfterTheRuleLeavesTheVertexUnlabelled) {
  // The counter seen as wall six times, then cabinet once: wall ruled out, cabinet's one vote
  // does not lead the rest by mesh_min_label_frames frames, so it stays unlabelled, not guessed.
  CounterAndWall world;
  TsdfConfig strict = rules(true, true, false);
  std::vector<Label> votes(6, Label::kWall);
  votes.push_back(Label::kCabinet);
  for (size_t v = 0; v < world.counter_vertices; ++v) world.set_votes(v, votes);
  world.mesh.vertices.labels = surface_labels(world.map, world.mesh.vertices.points);
  ASSERT_GT(world.share(0, world.counter_vertices, Label::kWall), 0.99);
  apply_label_priors(world.mesh, gravity(true), strict, SurfaceLabelEvidence(world.map, world.mesh.vertices.points));
  EXPECT_GT(world.share(0, world.counter_vertices, Label::kUnlabelled), 0.99);
}

TEST(LabelPriors, LikelyRuleNamesThinEvidenceWithinTheClassesItsSegmentShows) {
  // The counter seen once as cabinet (too thin for the frames' lead), the wall once as wall; a
  // row of each seen often (the classes the map shows), and one vertex of the counter's seen
  // once as cup.
  CounterAndWall world;
  const size_t counter = world.counter_vertices, all = world.mesh.vertices.points.size();
  for (size_t v = 0; v < all; ++v) world.set_votes(v, {v < counter ? Label::kCabinet : Label::kWall});
  const size_t counter_row = 11, wall_row = 25;  // vertices per row of the two planes
  for (size_t v = 0; v < counter_row; ++v) world.set_votes(v, std::vector<Label>(6, Label::kCabinet));
  for (size_t v = counter; v < counter + wall_row; ++v) world.set_votes(v, std::vector<Label>(6, Label::kWall));
  const size_t border = 5;
  world.set_votes(border, {Label::kCup});
  world.mesh.vertices.labels = surface_labels(world.map, world.mesh.vertices.points);
  ASSERT_GT(world.share(counter_row, counter, Label::kUnlabelled), 0.99);
  ASSERT_GT(world.share(counter + wall_row, all, Label::kUnlabelled), 0.99);
  const SurfaceLabelEvidence evidence(world.map, world.mesh.vertices.points);
  const LabelPriorStats s = apply_label_priors(world.mesh, gravity(true), rules(true, true, false, false, true), evidence);
  EXPECT_GT(world.share(0, counter, Label::kCabinet), 0.99);
  EXPECT_GT(world.share(counter, all, Label::kWall), 0.99);  // every triangle there is vertical
  EXPECT_GE(s.likely_filled, all - counter_row - wall_row - 1);
  // The cup vote is not taken: cup is a class the map shows nowhere, and its segment shows only cabinet.
  EXPECT_NE(world.mesh.vertices.labels[border], id(Label::kCup));
}

TEST(LabelPriors, StructureRuledOutWithNothingElseSeenIsOther) {
  // The counter seen six times as wall and nothing else: wall is ruled out (horizontal) and no
  // class fits, so it is an object the network does not name; the wall stays wall.
  CounterAndWall world, without;
  for (CounterAndWall* w : {&world, &without}) {
    for (size_t v = 0; v < w->mesh.vertices.points.size(); ++v) w->set_votes(v, std::vector<Label>(6, Label::kWall));
    w->mesh.vertices.labels = surface_labels(w->map, w->mesh.vertices.points);
  }
  const size_t counter = world.counter_vertices, all = world.mesh.vertices.points.size();
  const TsdfConfig with_other = rules(true, true, true, true, true, true), no_other = rules(true, true, true, true, true, false);
  const LabelPriorStats s =
      apply_label_priors(world.mesh, gravity(true), with_other, SurfaceLabelEvidence(world.map, world.mesh.vertices.points));
  apply_label_priors(without.mesh, gravity(true), no_other, SurfaceLabelEvidence(without.map, without.mesh.vertices.points));
  EXPECT_GT(world.share(0, counter, Label::kOther), 0.99);
  EXPECT_GT(without.share(0, counter, Label::kUnlabelled), 0.99);
  EXPECT_GT(world.share(counter, all, Label::kWall), 0.99);
  EXPECT_GE(s.other_filled, counter);
}

/// A fused floor at z = 0.5 m (sdf = height above it, observed within the truncation) whose
/// segmented frames' labels landed `offset_voxels` above it: their depth was nearer than the
/// fused surface, so the vertices' own voxels were never labelled (far, noisy depth). The
/// labelled voxels' sdf is `labelled_sdf_scale` times their distance from the floor: 0 puts them
/// on a surface of their own (a box standing on the floor), above 1 is noise on the far side.
struct FloorWithLabelsAbove {
  TsdfMap map;
  std::vector<Eigen::Vector3f> surface;  ///< points on the fused floor
  FloorWithLabelsAbove(double reach_voxels, int offset_voxels, float labelled_sdf_scale = 1.0f)
      : map(config(reach_voxels)) {
    const float s = static_cast<float>(map.config().voxel_size), z0 = 0.5f + 0.3f * s;
    const float c = static_cast<float>(map.config().bayes_default_confidence);
    for (int i = 0; i < 20; ++i)
      for (int j = 0; j < 20; ++j)
        for (int k = -8; k <= 8; ++k) {
          const VoxelIndex v = map.voxel_of_point(Eigen::Vector3f((i + 0.5f) * s, (j + 0.5f) * s, z0 + k * s));
          Block& block = map.allocate_block(block_of_voxel(v));
          TsdfVoxel& voxel = block.voxels[local_index(v)];
          voxel.weight_q = 10;
          voxel.set_sdf(map.voxel_centre(v).z() - z0);
          if (k != offset_voxels) continue;
          voxel.set_sdf(labelled_sdf_scale * voxel.sdf());
          uint8_t* bayes = &block.bayes[static_cast<size_t>(local_index(v)) * map.bayes().bytes_per_voxel()];
          for (int frame = 0; frame < 6; ++frame)
            map.bayes().update(bayes, ClassDistribution::from_label(id(Label::kFloor), c, map.config().bayes_confusion_classes));
        }
    for (int i = 2; i < 18; ++i)
      for (int j = 2; j < 18; ++j) surface.emplace_back((i + 0.25f) * s, (j + 0.75f) * s, z0);
  }
  static TsdfConfig config(double reach_voxels) {
    TsdfConfig c;
    c.label_evidence_reach_voxels = reach_voxels;
    return c;
  }
  double share_with_evidence_of(Label l) const {
    const SurfaceLabelEvidence evidence(map, surface);
    size_t n = 0;
    for (size_t i = 0; i < surface.size(); ++i) n += evidence.label_excluding(i, {}) == id(l);
    return double(n) / double(surface.size());
  }
};

TEST(LabelPriors, LabelsAFewVoxelsOffTheFusedSurfaceAreReadAlongItsNormal) {
  EXPECT_GT(FloorWithLabelsAbove(4.0, 3).share_with_evidence_of(Label::kFloor), 0.99);
  EXPECT_GT(FloorWithLabelsAbove(4.0, -3).share_with_evidence_of(Label::kFloor), 0.99);  // behind it too
  EXPECT_LT(FloorWithLabelsAbove(0.0, 3).share_with_evidence_of(Label::kFloor), 0.01);   // its own voxel only
  EXPECT_LT(FloorWithLabelsAbove(2.0, 3).share_with_evidence_of(Label::kFloor), 0.01);   // out of reach
  EXPECT_LT(FloorWithLabelsAbove(8.0, 6).share_with_evidence_of(Label::kFloor), 0.01);   // beyond the truncation
  EXPECT_LT(FloorWithLabelsAbove(4.0, 3, 0.0f).share_with_evidence_of(Label::kFloor), 0.01);  // another surface's
  EXPECT_LT(FloorWithLabelsAbove(4.0, 3, 0.5f).share_with_evidence_of(Label::kFloor), 0.01);  // nearer another one
  EXPECT_GT(FloorWithLabelsAbove(4.0, 3, 1.5f).share_with_evidence_of(Label::kFloor), 0.99);  // farther: noise
  EXPECT_GT(FloorWithLabelsAbove(4.0, -3, 1.5f).share_with_evidence_of(Label::kFloor), 0.99);
}

TEST(LabelPriors, FringesCloseSeamsWithinTheirReachAndStopAtACrease) {
  // A table top (0.75 m above the floor, 2 cm spacing) meeting a wall at x = 0. The voxels left
  // a seam where they meet: two profile vertices either side of the junction and the junction
  // itself unlabelled; and a 30 cm stretch in the middle of the table top.
  std::vector<Eigen::Vector2f> profile;
  std::vector<ClassId> truth, observed;
  const auto add = [&](float x, float z, Label l, bool seen) {
    profile.emplace_back(x, z), truth.push_back(id(l)), observed.push_back(seen ? id(l) : ClassId(0));
  };
  for (int i = 40; i >= 1; --i) add(-0.02f * i, 0.75f, Label::kTable, i > 2 && (i < 10 || i > 24));
  add(0.0f, 0.75f, Label::kTable, false);  // the junction
  for (int i = 1; i <= 40; ++i) add(0.0f, 0.75f + 0.02f * i, Label::kWall, i > 2);
  World w = bent_sheet(profile, truth, 1.0, 1);
  const int ny = 30;
  for (size_t k = 0; k < profile.size(); ++k)
    for (int j = 0; j <= ny; ++j) w.mesh.vertices.labels[k * (ny + 1) + j] = observed[k];
  const auto label_at = [&](const World& world, size_t k) { return world.mesh.vertices.labels[k * (ny + 1) + ny / 2]; };
  const size_t junction = 40;

  TsdfConfig c = rules(true, true, false, false, false, false, true);
  c.label_prior_fringe_m = 0.05;
  World reach_5cm = w;
  const LabelPriorStats s = apply_label_priors(reach_5cm.mesh, gravity(true), c);
  for (size_t k : {junction - 2, junction - 1}) EXPECT_EQ(label_at(reach_5cm, k), id(Label::kTable)) << k;
  for (size_t k : {junction + 1, junction + 2}) EXPECT_EQ(label_at(reach_5cm, k), id(Label::kWall)) << k;
  EXPECT_EQ(label_at(reach_5cm, junction), 0) << "6 cm from either side: out of reach";
  // The middle of the table top's gap: 2 and 4 cm from its labelled edges filled, the rest not.
  for (size_t k : {16u, 17u, 29u, 30u}) EXPECT_EQ(label_at(reach_5cm, k), id(Label::kTable)) << k;
  for (size_t k = 18; k <= 28; ++k) EXPECT_EQ(label_at(reach_5cm, k), 0) << k;
  EXPECT_EQ(s.fringe_filled, 8u * (ny + 1));

  // A class does not cross a crease, however far it may reach: with the wall never labelled,
  // the table's class stays on the table top.
  World bare_wall = w;
  for (size_t k = junction + 1; k < profile.size(); ++k)
    for (int j = 0; j <= ny; ++j) bare_wall.mesh.vertices.labels[k * (ny + 1) + j] = 0;
  c.label_prior_fringe_m = 0.5;
  apply_label_priors(bare_wall.mesh, gravity(true), c);
  for (size_t k = junction + 1; k < profile.size(); ++k) EXPECT_EQ(label_at(bare_wall, k), 0) << k;
  for (size_t k = 16; k <= 30; ++k) EXPECT_EQ(label_at(bare_wall, k), id(Label::kTable)) << k;
  // Switched off, nothing changes.
  c.label_prior_fringes = false;
  World off = w;
  apply_label_priors(off.mesh, gravity(true), c);
  EXPECT_EQ(off.mesh.vertices.labels, w.mesh.vertices.labels);
}

}  // namespace
}  // namespace semap
