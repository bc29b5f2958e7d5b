// bench_label_priors OUT...: the geometry-aware label rules (tsdf/label_priors.hpp, issue 38)
// each on and off, on maps saved by `semap run` (OUT/map.semap), without re-running the
// networks: the mesh is re-extracted from the saved voxels, the rules applied per variant, and
// the consistency figures of eval/consistency_metrics printed (one JSON line per variant).
// Also says why the unlabelled area is unlabelled: the voxel at each unlabelled vertex was never
// labelled, or its argmax is below tsdf.mesh_min_label_probability, or it does not lead the
// runner-up by tsdf.mesh_min_label_frames frames' votes (area shares of the mesh).
// SEMAP_BENCH_MESH_DIR=DIR also writes each variant's mesh there (DIR/MAP_FRAMES_VARIANT.ply), to look at.
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>

#include "semap/eval/consistency_metrics.hpp"
#include "semap/io/ply_io.hpp"
#include "semap/mapper.hpp"
#include "tsdf/label_priors.hpp"
#include "tsdf/map_io.hpp"
#include "tsdf/mesh_extractor.hpp"
#include "tsdf/tsdf_interpolation.hpp"

using namespace semap;

namespace {

std::vector<double> vertex_areas(const TriangleMesh& mesh) {
  std::vector<double> a(mesh.vertices.points.size(), 0.0);
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    for (uint32_t v : mesh.triangles[t]) a[v] += triangle_geometry(mesh, t).area_m2 / 3.0;
  return a;
}

nlohmann::json why_unlabelled(const TsdfMap& map, const TriangleMesh& mesh) {
  const std::vector<double> area = vertex_areas(mesh);
  double total = 0, never = 0, low_p = 0, low_lead = 0, unobserved = 0, other = 0;
  const BayesLayerCodec& codec = map.bayes();
  const float min_p = static_cast<float>(map.config().mesh_min_label_probability);
  CachedVoxelLookup lookup(map);
  for (size_t v = 0; v < area.size(); ++v) {
    total += area[v];
    if (mesh.vertices.labels[v] != 0) continue;
    const Block* block = nullptr;
    int li = 0;
    if (!lookup.observed(map.voxel_of_point(mesh.vertices.points[v]), &block, &li)) {
      unobserved += area[v];
      continue;
    }
    const uint8_t* bayes = &block->bayes[size_t(li) * codec.bytes_per_voxel()];
    if (bayes[0] == 0) never += area[v];
    else if (codec.decode(bayes[1]) < min_p) low_p += area[v];
    else low_lead += area[v];
    if (bayes[0] == id(Label::kOther)) other += area[v];
  }
  return {{"unlabelled_never_labelled", never / total},   {"unlabelled_below_probability", low_p / total},
          {"unlabelled_below_lead", low_lead / total},    {"unlabelled_voxel_unobserved", unobserved / total},
          {"unlabelled_argmax_other", other / total}};
}

nlohmann::json figures(const TriangleMesh& mesh, const Trajectory& trajectory) {
  const SemanticConsistency c = evaluate_consistency(mesh, trajectory);
  return {{"labelled", c.labelled_area_share}, {"floor_agreement", c.floor.facing_agreement},
          {"wall_agreement", c.wall.agreement}, {"ceiling_agreement", c.ceiling.facing_agreement},
          {"floor_area_share", c.floor.area_share}, {"floor_thickness_m", c.floor_thickness_m.value_or(-1.0)}};
}

}  // namespace

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::filesystem::path dir = argv[i];
    const Trajectory trajectory = Mapper::load(dir / "map.semap")->trajectory();
    struct Threshold {
      double probability;
      int frames;
    };
    for (const Threshold& th : {Threshold{-1, -1}, Threshold{0.6, 1}, Threshold{0.5, 0}}) {
      TsdfConfig base;
      if (th.frames >= 0) {
        base.mesh_min_label_probability = th.probability;
        base.mesh_min_label_frames = th.frames;
      }
      const TsdfMap map = load_map(dir / "map.semap", base);
      const TriangleMesh raw = MeshExtractor().extract_full(map);
      if (map.has_bayes_layer() && th.frames < 0)
        std::printf("%s\n", nlohmann::json{{"map", dir}, {"why", why_unlabelled(map, raw)}}.dump().c_str());
      const GravityEstimate gravity = estimate_gravity(raw, trajectory);
      struct Variant {
        const char* name;
        bool normals, heights, regions, evidence, segments, likely, other, fringes;
      };
      const SurfaceLabelEvidence evidence(map, raw.vertices.points);
      for (const Variant& v : {Variant{"none", false, false, false, false, false, false, false, false},
                               Variant{"normals", true, false, false, false, false, false, false, false},
                               Variant{"heights", false, true, false, false, false, false, false, false},
                               Variant{"regions", false, false, true, false, false, false, false, false},
                               Variant{"segments", false, false, false, false, true, false, false, false},
                               Variant{"normals+heights", true, true, false, false, false, false, false, false},
                               Variant{"normals+heights+evidence", true, true, false, true, false, false, false, false},
                               Variant{"all but evidence", true, true, true, false, true, true, true, true},
                               Variant{"all but segments", true, true, true, true, false, true, true, true},
                               Variant{"all but likely", true, true, true, true, true, false, true, true},
                               Variant{"all but other", true, true, true, true, true, true, false, true},
                               Variant{"all but fringes", true, true, true, true, true, true, true, false},
                               Variant{"all", true, true, true, true, true, true, true, true}}) {
        TsdfConfig c = map.config();
        c.label_prior_normals = v.normals;
        c.label_prior_heights = v.heights;
        c.label_prior_regions = v.regions;
        c.label_prior_segments = v.segments;
        c.label_prior_likely = v.likely;
        c.label_prior_other = v.other;
        c.label_prior_fringes = v.fringes;
        TriangleMesh mesh = raw;
        const LabelPriorStats s = apply_label_priors(mesh, gravity, c, v.evidence ? evidence : SurfaceLabelEvidence{});
        nlohmann::json j{{"map", dir.filename()}, {"min_p", map.config().mesh_min_label_probability},
                         {"min_frames", map.config().mesh_min_label_frames}, {"rules", v.name}};
        j.update(figures(mesh, trajectory));
        j["floor_found"] = gravity.floor_found;
        j["contradicting"] = s.contradicting;
        j["filled"] = s.filled;
        j["replaced"] = s.replaced;
        j["refitted"] = s.refitted;
        j["segment_filled"] = s.segment_filled;
        j["likely_filled"] = s.likely_filled;
        j["other_filled"] = s.other_filled;
        j["fringe_filled"] = s.fringe_filled;
        j["regions"] = s.regions;
        j["region_area_share"] = s.region_area_m2 / evaluate_consistency(raw, trajectory).mesh_area_m2;
        std::printf("%s\n", j.dump().c_str());
        if (const char* mesh_dir = std::getenv("SEMAP_BENCH_MESH_DIR"))  // for looking at a variant
          write_ply(std::filesystem::path(mesh_dir) / (dir.filename().string() + "_" + std::to_string(th.frames) + "_" +
                                                       v.name + ".ply"), mesh);
      }
    }
  }
  return 0;
}
