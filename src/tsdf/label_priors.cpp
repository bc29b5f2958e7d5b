#include "tsdf/label_priors.hpp"

#include <algorithm>
#include <bitset>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "core/graph_segmentation.hpp"

namespace semap {

namespace {

enum class Facing : uint8_t { kOther, kUp, kDown, kVertical };

struct Geometry {
  std::vector<Eigen::Vector3d> vertex_normal;    ///< area-weighted, unit (zero if isolated)
  std::vector<Eigen::Vector3d> triangle_normal;  ///< mean of its vertices' normals, unit
  std::vector<Eigen::Vector3d> centroid;
  std::vector<Eigen::Vector3d> face_normal;      ///< the triangle's own, unit (as wound)
  std::vector<double> area_m2;
  std::vector<double> vertex_area_m2;            ///< a third of its triangles' area
  std::vector<uint32_t> first, incident;         ///< vertex -> triangles (CSR)
};

Geometry mesh_geometry(const TriangleMesh& mesh) {
  Geometry g;
  const size_t nv = mesh.vertices.points.size(), nt = mesh.triangles.size();
  g.vertex_normal.assign(nv, Eigen::Vector3d::Zero());
  g.triangle_normal.resize(nt);
  g.centroid.resize(nt);
  g.face_normal.resize(nt);
  g.area_m2.resize(nt);
  g.first.assign(nv + 1, 0);
  for (size_t t = 0; t < nt; ++t) {
    const TriangleGeometry tg = triangle_geometry(mesh, t);
    g.centroid[t] = tg.centroid;
    g.face_normal[t] = tg.normal;
    g.area_m2[t] = tg.area_m2;
    for (uint32_t v : mesh.triangles[t]) {
      g.vertex_normal[v] += tg.area_m2 * tg.normal;  // area-weighted
      ++g.first[v + 1];
    }
  }
  for (auto& n : g.vertex_normal)
    if (n.norm() > 0) n.normalize();
  for (size_t v = 0; v < nv; ++v) g.first[v + 1] += g.first[v];
  g.incident.resize(g.first[nv]);
  std::vector<uint32_t> fill(g.first.begin(), g.first.end() - 1);
  for (size_t t = 0; t < nt; ++t) {
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    for (uint32_t v : mesh.triangles[t]) {
      g.incident[fill[v]++] = static_cast<uint32_t>(t);
      n += g.vertex_normal[v];
    }
    g.triangle_normal[t] = n.norm() > 0 ? n.normalized() : n;
  }
  g.vertex_area_m2.assign(nv, 0.0);
  for (size_t t = 0; t < nt; ++t)
    for (uint32_t v : mesh.triangles[t]) g.vertex_area_m2[v] += g.area_m2[t] / 3.0;
  return g;
}

Facing facing(const Eigen::Vector3d& n, const Eigen::Vector3d& up, double cos_tilt, double sin_tilt) {
  const double c = n.dot(up);
  if (c >= cos_tilt) return Facing::kUp;
  if (c <= -cos_tilt) return Facing::kDown;
  if (std::fabs(c) <= sin_tilt && n.squaredNorm() > 0) return Facing::kVertical;
  return Facing::kOther;
}

/// The class rules of the file comment: does `label` fit a surface facing `f` at `height_m`
/// above the floor (NaN: no floor known)?
struct ClassRules {
  bool normals, heights;
  double floor_band_m, min_ceiling_m;
  bool fits(ClassId label, Facing f, double height_m) const {
    const bool floor_known = heights && std::isfinite(height_m);
    if (label == id(Label::kFloor))
      return (!normals || f == Facing::kUp) && (!floor_known || std::fabs(height_m) <= floor_band_m);
    if (label == id(Label::kCeiling))
      return (!normals || f == Facing::kDown) && (!floor_known || height_m >= min_ceiling_m);
    if (label == id(Label::kWall)) return !normals || f == Facing::kVertical;
    return true;
  }
};

bool is_structural(ClassId c) { return c == id(Label::kWall) || c == id(Label::kFloor) || c == id(Label::kCeiling); }
/// Classes that may lie in a wall, floor or ceiling plane: surface coverings and openings.
bool may_lie_in_plane(ClassId c) { return c == 0 || is_stuff(c) || c == id(Label::kPicture); }

struct Region {
  Facing facing = Facing::kOther;
  double area_m2 = 0.0;
  Eigen::Vector3d normal_sum = Eigen::Vector3d::Zero(), point_sum = Eigen::Vector3d::Zero();
  std::vector<uint32_t> triangles;
};

/// Grows the planar gravity-aligned regions (file comment) over triangles sharing a vertex.
std::vector<Region> grow_regions(const TriangleMesh& mesh, const Geometry& g, const std::vector<Facing>& tri_facing,
                                 const TsdfConfig& c) {
  const double cos_region = std::cos(c.label_prior_region_normal_deg * std::numbers::pi / 180.0);
  std::vector<int32_t> region_of(mesh.triangles.size(), -1);
  std::vector<Region> regions;
  std::vector<uint32_t> queue;
  for (size_t seed = 0; seed < mesh.triangles.size(); ++seed) {
    if (region_of[seed] >= 0 || tri_facing[seed] == Facing::kOther || g.area_m2[seed] <= 0) continue;
    Region r;
    r.facing = tri_facing[seed];
    const auto add = [&](uint32_t t) {
      region_of[t] = static_cast<int32_t>(regions.size());
      r.triangles.push_back(t);
      r.area_m2 += g.area_m2[t];
      r.normal_sum += g.area_m2[t] * g.triangle_normal[t];
      r.point_sum += g.area_m2[t] * g.centroid[t];
    };
    add(static_cast<uint32_t>(seed));
    queue.assign(1, static_cast<uint32_t>(seed));
    while (!queue.empty()) {
      const uint32_t t = queue.back();
      queue.pop_back();
      const Eigen::Vector3d n = r.normal_sum.normalized(), p = r.point_sum / r.area_m2;
      for (uint32_t v : mesh.triangles[t])
        for (uint32_t k = g.first[v]; k < g.first[v + 1]; ++k) {
          const uint32_t u = g.incident[k];
          if (region_of[u] >= 0 || tri_facing[u] != r.facing || g.area_m2[u] <= 0) continue;
          if (g.triangle_normal[u].dot(n) < cos_region) continue;
          if (std::fabs(n.dot(g.centroid[u] - p)) > c.label_prior_region_plane_m) continue;
          add(u);
          queue.push_back(u);
        }
    }
    if (r.area_m2 >= c.label_prior_region_min_area_m2) regions.push_back(std::move(r));
    else
      for (uint32_t t : r.triangles) region_of[t] = -2;  // too small: never a seed or member again
  }
  return regions;
}

/// The class that decides a region: a horizontal region facing up at the floor height is floor
/// (rug where more of it is labelled rug), one facing down at ceiling height is ceiling: the
/// lowest and highest large horizontal surfaces. Any other region: the fitting class with the
/// most area, when it holds region_min_share of the fitting labelled area; else 0.
ClassId region_class(const TriangleMesh& mesh, const Geometry& g, const Region& r, const ClassRules& rules,
                     const GravityEstimate& gravity, const TsdfConfig& c) {
  std::vector<double> area(kNumClasses, 0.0);
  for (uint32_t t : r.triangles) {
    const ClassId l = triangle_label(mesh, t);
    if (l != 0 && l < kNumClasses) area[l] += g.area_m2[t];
  }
  const double height = gravity.floor_found ? gravity.up_W.dot(r.point_sum / r.area_m2) - gravity.floor_height_m
                                            : std::nan("");
  if (c.label_prior_heights && gravity.floor_found) {
    if (r.facing == Facing::kUp && std::fabs(height) <= c.label_prior_floor_band_m)
      return area[id(Label::kRug)] > area[id(Label::kFloor)] ? id(Label::kRug) : id(Label::kFloor);
    if (r.facing == Facing::kDown && height >= c.label_prior_min_ceiling_height_m) return id(Label::kCeiling);
  }
  ClassId best = 0;
  double fitting = 0.0;
  for (int l = 1; l < kNumClasses; ++l) {
    if (!rules.fits(ClassId(l), r.facing, height)) continue;
    fitting += area[l];
    if (area[l] > area[best]) best = ClassId(l);
  }
  return best != 0 && area[best] >= c.label_prior_region_min_share * fitting ? best : 0;
}


/// Smooth segments (file comment): Felzenszwalb-Huttenlocher over the mesh's vertex edges, each
/// weighted by the normal difference 1 - n_u.n_v. Returns a segment id per vertex.
std::vector<int> smooth_segments(const TriangleMesh& mesh, const Geometry& g, double k) {
  std::vector<WeightedEdge> edges;
  edges.reserve(mesh.triangles.size() * 3);
  for (const auto& tri : mesh.triangles)
    for (int i = 0; i < 3; ++i) {
      const uint32_t a = tri[i], b = tri[(i + 1) % 3];
      edges.push_back({static_cast<int>(a), static_cast<int>(b),
                       static_cast<float>(1.0 - g.vertex_normal[a].dot(g.vertex_normal[b]))});
    }
  // Small segments stay apart: ScanNet's annotation tool joins those under 20 vertices to a
  // neighbour whatever the normal turn between them, which here carried a table's class onto
  // the bottles and the monitor on it (semap demo mIoU 0.931 against 0.947 without the joins).
  return felzenszwalb_cluster(static_cast<int>(mesh.vertices.points.size()), std::move(edges), static_cast<float>(k));
}

int segment_count(const std::vector<int>& segment) {
  return segment.empty() ? 0 : *std::max_element(segment.begin(), segment.end()) + 1;
}

/// The segments' rule (file comment) on the vertices still unlabelled. Returns how many it labelled.
size_t fill_from_segments(TriangleMesh& mesh, const Geometry& g, const std::vector<int>& segment, const TsdfConfig& c) {
  auto& labels = mesh.vertices.labels;
  const size_t nv = labels.size();
  const int num_segments = segment_count(segment);
  // The vertices of each segment (CSR).
  std::vector<uint32_t> first(num_segments + 1, 0), members(nv);
  for (int s : segment) ++first[s + 1];
  for (int s = 0; s < num_segments; ++s) first[s + 1] += first[s];
  std::vector<uint32_t> fill(first.begin(), first.end() - 1);
  for (size_t v = 0; v < nv; ++v) members[fill[segment[v]]++] = static_cast<uint32_t>(v);
  const std::vector<double>& vertex_area = g.vertex_area_m2;

  size_t filled = 0;
  std::vector<double> area(kNumClasses);
  for (int s = 0; s < num_segments; ++s) {
    std::fill(area.begin(), area.end(), 0.0);
    double total = 0.0, labelled = 0.0;
    for (uint32_t k = first[s]; k < first[s + 1]; ++k) {
      const uint32_t v = members[k];
      total += vertex_area[v];
      if (labels[v] != 0 && labels[v] < kNumClasses) area[labels[v]] += vertex_area[v], labelled += vertex_area[v];
    }
    const ClassId best = static_cast<ClassId>(std::max_element(area.begin(), area.end()) - area.begin());
    // Wall, floor and ceiling are decided by the planar regions above, not spread along smooth
    // segments (a counter front the network half calls wall would become a wall).
    if (best == 0 || is_structural(best) || labelled < c.label_prior_segment_min_labelled * total ||
        area[best] < c.label_prior_region_min_share * labelled)
      continue;
    for (uint32_t k = first[s]; k < first[s + 1]; ++k) {
      const uint32_t v = members[k];
      if (labels[v] != 0) continue;
      labels[v] = best;
      ++filled;
    }
  }
  return filled;
}


/// The map's own class frequencies: each class's share of the labelled area, plus
/// kUnseenClassShare, so that a class the map shows nowhere needs far stronger evidence to appear.
std::array<float, kNumClasses> scene_class_prior(const std::vector<ClassId>& labels, const Geometry& g) {
  constexpr double kUnseenClassShare = 1e-3;
  std::array<double, kNumClasses> area{};
  double labelled = 0.0;
  for (size_t v = 0; v < labels.size(); ++v)
    if (labels[v] != 0 && labels[v] < kNumClasses) area[labels[v]] += g.vertex_area_m2[v], labelled += g.vertex_area_m2[v];
  std::array<float, kNumClasses> prior{};
  for (int c = 1; c < kNumClasses; ++c)
    prior[c] = static_cast<float>((labelled > 0.0 ? area[c] / labelled : 0.0) + kUnseenClassShare);
  return prior;
}

using ClassSet = std::bitset<kNumClasses>;

/// The classes each smooth segment's labelled vertices show.
std::vector<ClassSet> segment_classes(const std::vector<ClassId>& labels, const std::vector<int>& segment) {
  std::vector<ClassSet> shown(segment_count(segment));
  for (size_t v = 0; v < labels.size(); ++v)
    if (labels[v] != 0 && labels[v] < kNumClasses) shown[segment[v]].set(labels[v]);
  return shown;
}

/// A structural region's plane and extent: a vertex near it lies at its junction with another surface.
struct StructuralPlane {
  Eigen::Vector3d normal, point;
  Eigen::AlignedBox3d box;
};

StructuralPlane structural_plane(const TriangleMesh& mesh, const Region& r) {
  StructuralPlane s{r.normal_sum.normalized(), r.point_sum / r.area_m2, {}};
  for (uint32_t t : r.triangles)
    for (uint32_t v : mesh.triangles[t]) s.box.extend(mesh.vertices.points[v].cast<double>());
  return s;
}

bool near_structure(const std::vector<StructuralPlane>& planes, const Eigen::Vector3d& x, double plane_m) {
  for (const StructuralPlane& s : planes)
    if (std::fabs(s.normal.dot(x - s.point)) <= plane_m && s.box.exteriorDistance(x) <= plane_m) return true;
  return false;
}

/// What every rule reads: the mesh's geometry, up, the floor and the class rules.
struct Surface {
  const TriangleMesh& mesh;
  Geometry g;
  Eigen::Vector3d up;
  const GravityEstimate& gravity;
  ClassRules rules;
  double cos_tilt, sin_tilt;

  Surface(const TriangleMesh& m, const GravityEstimate& gr, const TsdfConfig& c)
      : mesh(m), g(mesh_geometry(m)), up(gr.up_W.normalized()), gravity(gr),
        rules{c.label_prior_normals, c.label_prior_heights, c.label_prior_floor_band_m, c.label_prior_min_ceiling_height_m} {
    const double tilt = c.label_prior_max_tilt_deg * std::numbers::pi / 180.0;
    cos_tilt = std::cos(tilt), sin_tilt = std::sin(tilt);
  }
  double height(size_t v) const {
    return gravity.floor_found ? up.dot(mesh.vertices.points[v].cast<double>()) - gravity.floor_height_m : std::nan("");
  }
  Facing vertex_facing(size_t v) const { return facing(g.vertex_normal[v], up, cos_tilt, sin_tilt); }
  /// Marks the structural classes vertex v's smoothed normal or height rules out; false when none.
  bool rule_out_at(size_t v, std::array<bool, kNumClasses>& ruled_out) const {
    return rule_out(vertex_facing(v), height(v), ruled_out);
  }
  /// ... and those that any triangle around v rules out (its own normal, not the smoothed one).
  void rule_out_around(size_t v, std::array<bool, kNumClasses>& ruled_out) const {
    const double h = height(v);
    rule_out(vertex_facing(v), h, ruled_out);
    for (uint32_t k = g.first[v]; k < g.first[v + 1]; ++k)
      rule_out(facing(g.face_normal[g.incident[k]], up, cos_tilt, sin_tilt), h, ruled_out);
  }

 private:
  /// Adds the structural classes a surface facing `f` at `height_m` rules out; true when any.
  bool rule_out(Facing f, double height_m, std::array<bool, kNumClasses>& ruled_out) const {
    bool any = false;
    for (Label structural : {Label::kWall, Label::kFloor, Label::kCeiling})
      if (!rules.fits(id(structural), f, height_m)) any = ruled_out[id(structural)] = true;
    return any;
  }
};

/// The class rules, per vertex (its smoothed normal, its height): 1 where the label contradicts.
std::vector<uint8_t> find_contradictions(const Surface& s, const std::vector<ClassId>& labels, LabelPriorStats& stats) {
  std::vector<uint8_t> contradicts(labels.size(), 0);
  for (size_t v = 0; v < labels.size(); ++v)
    if (labels[v] != 0 && !s.rules.fits(labels[v], s.vertex_facing(v), s.height(v))) {
      contradicts[v] = 1;
      ++stats.contradicting;
    }
  return contradicts;
}

/// The regions' rule (file comment), from the labels before the class rules removed any. Returns
/// the planes of the regions it decided wall, floor or ceiling.
std::vector<StructuralPlane> decide_regions(const Surface& s, std::vector<ClassId>& labels, std::vector<uint8_t>& contradicts,
                                            const TsdfConfig& c, LabelPriorStats& stats) {
  std::vector<Facing> tri_facing(s.mesh.triangles.size());
  for (size_t t = 0; t < tri_facing.size(); ++t) tri_facing[t] = facing(s.g.triangle_normal[t], s.up, s.cos_tilt, s.sin_tilt);
  const std::vector<Region> regions = grow_regions(s.mesh, s.g, tri_facing, c);
  std::vector<StructuralPlane> structure;
  std::vector<uint8_t> done(labels.size(), 0);
  for (const Region& region : regions) {
    const ClassId cls = region_class(s.mesh, s.g, region, s.rules, s.gravity, c);
    if (cls == 0) continue;
    if (is_structural(cls)) structure.push_back(structural_plane(s.mesh, region));
    ++stats.regions;
    stats.region_area_m2 += region.area_m2;
    for (uint32_t t : region.triangles)
      for (uint32_t v : s.mesh.triangles[t]) {
        if (done[v]) continue;
        done[v] = 1;
        const ClassId old = labels[v];
        if (old == cls) continue;
        if (old == 0 || contradicts[v]) {
          ++stats.filled;
        } else if (is_structural(cls) && !may_lie_in_plane(old)) {
          ++stats.replaced;
        } else {
          continue;
        }
        labels[v] = cls;
        contradicts[v] = 0;
      }
  }
  return structure;
}

/// Unlabels what still contradicts; with `evidence`, gives it (and any unlabelled vertex where
/// the geometry rules a class out) the class the evidence shows among the fitting ones.
void refit_from_evidence(const Surface& s, std::vector<ClassId>& labels, const std::vector<uint8_t>& contradicts,
                         const SurfaceLabelEvidence& evidence, LabelPriorStats& stats) {
  for (size_t v = 0; v < labels.size(); ++v) {
    if (!contradicts[v] && labels[v] != 0) continue;
    if (contradicts[v]) labels[v] = 0;
    std::array<bool, kNumClasses> ruled_out{};
    if (evidence.size() != labels.size() || !s.rule_out_at(v, ruled_out)) continue;  // the voxel's decision stands
    labels[v] = evidence.label_excluding(v, ruled_out);
    stats.refitted += labels[v] != 0;
  }
}

/// The likely rule (file comment) on the vertices still unlabelled.
void fill_likely(const Surface& s, std::vector<ClassId>& labels, const std::vector<int>& segment,
                 const SurfaceLabelEvidence& evidence, const TsdfConfig& c, LabelPriorStats& stats) {
  const std::array<float, kNumClasses> prior = scene_class_prior(labels, s.g);
  const std::vector<ClassSet> confident = segment_classes(labels, segment);
  for (size_t v = 0; v < labels.size(); ++v) {
    if (labels[v] != 0) continue;
    // Wall, floor and ceiling need every triangle around the vertex to fit: thin evidence on a
    // noisy surface must not tilt the structure.
    std::array<bool, kNumClasses> ruled_out{};
    s.rule_out_around(v, ruled_out);
    const ClassId likely = evidence.likely_excluding(v, ruled_out, prior, static_cast<float>(c.label_prior_likely_probability));
    // Within a smooth segment that shows confident classes, only those: a border vertex whose
    // voxel also saw the neighbouring object does not take its class.
    const ClassSet& shown = confident[segment[v]];
    if (likely == 0 || (shown.any() && !shown.test(likely))) continue;
    labels[v] = likely;
    ++stats.likely_filled;
  }
}

/// The `other` rule (file comment): contradicted, still unlabelled, away from the structure's junctions.
void fill_other(const Surface& s, std::vector<ClassId>& labels, const std::vector<uint8_t>& contradicts,
                const std::vector<StructuralPlane>& structure, const TsdfConfig& c, LabelPriorStats& stats) {
  for (size_t v = 0; v < labels.size(); ++v)
    if (labels[v] == 0 && contradicts[v] &&
        !near_structure(structure, s.mesh.vertices.points[v].cast<double>(), c.label_prior_region_plane_m)) {
      labels[v] = id(Label::kOther);
      ++stats.other_filled;
    }
}

/// The fringes' rule (file comment). `reach_m`: how far along the mesh each vertex lies from
/// where its class was decided (0: labelled by an earlier rule or the voxels).
void fill_fringes(const Surface& s, std::vector<ClassId>& labels, const std::vector<int>& segment, const TsdfConfig& c,
                  LabelPriorStats& stats) {
  const size_t nv = labels.size();
  const auto& points = s.mesh.vertices.points;
  std::vector<float> reach_m(nv, std::numeric_limits<float>::infinity());
  for (size_t v = 0; v < nv; ++v)
    if (labels[v] != 0) reach_m[v] = 0.0f;
  // Calls f(u) once per vertex u sharing a triangle with v (the pass's stamp dedupes shared edges).
  std::vector<uint32_t> stamp(nv, std::numeric_limits<uint32_t>::max());
  uint32_t pass = 0;
  const auto for_each_neighbour = [&](uint32_t v, auto&& f) {
    ++pass;
    for (uint32_t k = s.g.first[v]; k < s.g.first[v + 1]; ++k)
      for (uint32_t u : s.mesh.triangles[s.g.incident[k]])
        if (u != v && stamp[u] != pass) stamp[u] = pass, f(u);
  };
  struct Decision {
    uint32_t vertex;
    ClassId cls;
    float reach_m;
  };
  std::vector<Decision> ring;
  std::vector<uint32_t> frontier;
  for (uint32_t v = 0; v < nv; ++v)
    if (labels[v] == 0) frontier.push_back(v);
  while (!frontier.empty()) {
    ring.clear();
    for (uint32_t v : frontier) {
      std::array<double, kNumClasses> votes{};
      std::array<float, kNumClasses> reach;
      reach.fill(std::numeric_limits<float>::infinity());
      for_each_neighbour(v, [&](uint32_t u) {
        const ClassId l = labels[u];
        if (l == 0 || l >= kNumClasses || segment[u] != segment[v]) return;
        const float d = reach_m[u] + (points[u] - points[v]).norm();
        if (d > c.label_prior_fringe_m) return;
        votes[l] += s.g.vertex_area_m2[u];
        reach[l] = std::min(reach[l], d);
      });
      if (std::all_of(votes.begin(), votes.end(), [](double w) { return w == 0.0; })) continue;  // nothing in reach
      std::array<bool, kNumClasses> ruled_out{};
      s.rule_out_around(v, ruled_out);
      for (int l = 1; l < kNumClasses; ++l)
        if (ruled_out[l]) votes[l] = 0.0;
      const auto best = static_cast<ClassId>(std::max_element(votes.begin() + 1, votes.end()) - votes.begin());
      if (votes[best] > 0.0) ring.push_back({v, best, reach[best]});
    }
    // One ring at a time: a class spreads outward from where it was decided, not along the scan order.
    frontier.clear();
    for (const Decision& d : ring) {
      labels[d.vertex] = d.cls;
      reach_m[d.vertex] = d.reach_m;
      ++stats.fringe_filled;
    }
    for (const Decision& d : ring)
      for_each_neighbour(d.vertex, [&](uint32_t u) {
        if (labels[u] == 0) frontier.push_back(u);
      });
    std::sort(frontier.begin(), frontier.end());
    frontier.erase(std::unique(frontier.begin(), frontier.end()), frontier.end());
  }
}

}  // namespace

LabelPriorStats apply_label_priors(TriangleMesh& mesh, const GravityEstimate& gravity, const TsdfConfig& c,
                                   const SurfaceLabelEvidence& evidence) {
  LabelPriorStats stats;
  auto& labels = mesh.vertices.labels;
  if (labels.size() != mesh.vertices.points.size() || mesh.triangles.empty()) return stats;
  if (!c.label_prior_normals && !c.label_prior_heights && !c.label_prior_regions && !c.label_prior_segments &&
      !c.label_prior_likely && !c.label_prior_other && !c.label_prior_fringes)
    return stats;
  const Surface s(mesh, gravity, c);
  std::vector<uint8_t> contradicts = find_contradictions(s, labels, stats);
  std::vector<StructuralPlane> structure;
  if (c.label_prior_regions) structure = decide_regions(s, labels, contradicts, c, stats);
  const bool geometry = c.label_prior_normals || c.label_prior_heights;
  refit_from_evidence(s, labels, contradicts, geometry ? evidence : SurfaceLabelEvidence{}, stats);
  const bool use_segments = c.label_prior_segments || c.label_prior_likely || c.label_prior_fringes;
  const std::vector<int> segment = use_segments ? smooth_segments(mesh, s.g, c.label_prior_segment_k) : std::vector<int>{};
  if (c.label_prior_likely && evidence.size() == labels.size()) fill_likely(s, labels, segment, evidence, c, stats);
  if (c.label_prior_segments) stats.segment_filled = fill_from_segments(mesh, s.g, segment, c);
  if (c.label_prior_other) fill_other(s, labels, contradicts, structure, c, stats);
  if (c.label_prior_fringes) fill_fringes(s, labels, segment, c, stats);
  return stats;
}

}  // namespace semap
