// The issue's quality figures: the synthetic world (GT poses + GT labels, and 20 % flicker
// noisy labels) against gt_points.ply, and a sanity fuse of tum_fr1_rpy with GT poses.
// SEMAP_TSDF_HEAVY builds the longer variants (more frames, 640x480).
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <map>

#include "semap/eval/semantic_metrics.hpp"
#include "semap/io/dataset.hpp"
#include "semap/io/ply_io.hpp"
#include "synth/synth_config.hpp"
#include "test_support.hpp"
#include "tsdf/semantic_tsdf.hpp"

namespace semap {
namespace {

#ifdef SEMAP_TSDF_HEAVY
constexpr int kFrames = 300, kWidth = 640, kHeight = 480, kTumFrames = 400;
#else
constexpr int kFrames = 90, kWidth = 320, kHeight = 240, kTumFrames = 60;
#endif

const std::filesystem::path& synthetic_dataset() {
  static test::TempDir dir("tsdf_synth");
  static const std::filesystem::path path = [] {
    if (const char* existing = std::getenv("SEMAP_TSDF_SYNTH_DIR")) return std::filesystem::path(existing);
    SynthConfig cfg;
    cfg.frames = kFrames;
    cfg.width = kWidth;
    cfg.height = kHeight;
    cfg.seed = 3;
    cfg.seg_noise = 0.2;
    const auto out = dir / "world";
    generate_dataset(cfg, out);
    return out;
  }();
  return path;
}

struct FuseResult {
  TriangleMesh mesh;
  double ms_per_frame = 0;
};

FuseResult fuse_dataset(const std::filesystem::path& root, TsdfConfig cfg, bool noisy_labels, int max_frames,
                        bool use_labels = true) {
  DatasetOptions options;
  options.noisy_labels = noisy_labels;
  auto reader = open_dataset(root, options);
  SemanticTsdf tsdf(cfg);
  const size_t n = std::min<size_t>(reader->size(), max_frames);
  double ms = 0;
  for (size_t i = 0; i < n; ++i) {
    Frame frame = reader->load(i);
    if (!frame.gt_T_world_camera) continue;
    IntegrationInput in = make_integration_input(frame, reader->camera().depth, *frame.gt_T_world_camera);
    if (!use_labels) in.labels = cv::Mat();
    const auto t0 = std::chrono::steady_clock::now();
    tsdf.integrate(in);
    ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  }
  FuseResult r;
  r.mesh = tsdf.extract_mesh();
  r.ms_per_frame = ms / std::max<size_t>(n, 1);
  return r;
}

SemanticEvaluation evaluate(const TriangleMesh& mesh) {
  const TriangleMesh gt = read_ply(synthetic_dataset() / "gt_points.ply");
  return evaluate_semantic(gt.vertices, mesh.vertices);
}

void print(const std::string& what, const SemanticEvaluation& e, double ms) {
  std::cout << what << ": mean surface error " << e.surface_error_mean_m * 1000 << " mm, completeness "
            << e.completeness << ", mIoU " << e.miou << ", vertices " << e.map_vertices << ", " << ms
            << " ms/frame\n  per class:";
  for (const ClassIoU& c : e.classes) std::cout << " " << class_name(c.class_id) << "=" << c.iou;
  std::cout << "\n";
}

class SyntheticQuality : public ::testing::TestWithParam<std::string> {};

TEST_P(SyntheticQuality, GroundTruthLabelsMeetTheIssueFigures) {
  TsdfConfig cfg;
  cfg.voxel_size = 0.02;
  cfg.integrator = *enum_value(kIntegratorNames, GetParam());
  const FuseResult r = fuse_dataset(synthetic_dataset(), cfg, false, kFrames);
  const SemanticEvaluation e = evaluate(r.mesh);
  print(GetParam() + " GT labels", e, r.ms_per_frame);
  EXPECT_LE(e.surface_error_mean_m, 0.01);
  EXPECT_GE(e.completeness, 0.95);
  EXPECT_GE(e.miou, 0.95);
}

/// Mesh vertices labelled with a class the ground truth never has (the eval counts such a class
/// with IoU 0): what 20 % region flicker leaves on rarely seen patches without an evidence rule.
size_t stray_class_vertices(const TriangleMesh& mesh) {
  const TriangleMesh gt = read_ply(synthetic_dataset() / "gt_points.ply");
  std::array<bool, kNumClasses> in_gt{};
  for (ClassId c : gt.vertices.labels) in_gt[c] = true;
  size_t n = 0;
  for (ClassId c : mesh.vertices.labels) n += c != 0 && !in_gt[c];
  return n;
}

TEST_P(SyntheticQuality, NoisyLabelsBayesianLayerAndCompactRule) {
#ifndef SEMAP_TSDF_HEAVY
  if (GetParam() != "grouped") GTEST_SKIP() << "projective noisy case: heavy suite only";
#endif
  // 20 % per-frame region flicker (the synth generator's label_noisy/). The Bayesian layer shows
  // its argmax only when it leads the runner-up by three frames' votes (mesh_min_label_frames):
  // a patch seen in a few frames, some of which flickered together (a whole wall turns
  // "ceiling" in a frame), otherwise shows a class the scene does not have, which the eval
  // counts with IoU 0. The compact vote shows a margin of 2 (mesh_min_label_votes).
  // Measured (seed 3): 90 frames 320x240 grouped Bayes 0.925 / vote 0.924; 300 frames 640x480
  // grouped Bayes 0.965 / vote 0.892 (2 stray-class vertices), projective Bayes 0.953 / vote 0.954.
  TsdfConfig cfg;
  cfg.voxel_size = 0.02;
  cfg.integrator = *enum_value(kIntegratorNames, GetParam());
  cfg.bayes_layer = true;  // mesh labels come from the Bayesian argmax
  const FuseResult bayes = fuse_dataset(synthetic_dataset(), cfg, true, kFrames);
  const SemanticEvaluation eb = evaluate(bayes.mesh);
  print(GetParam() + " noisy labels, Bayesian layer", eb, bayes.ms_per_frame);
  std::cout << "  stray-class vertices: " << stray_class_vertices(bayes.mesh) << "\n";
  cfg.bayes_layer = false;  // compact majority vote
  const FuseResult compact = fuse_dataset(synthetic_dataset(), cfg, true, kFrames);
  const SemanticEvaluation ec = evaluate(compact.mesh);
  print(GetParam() + " noisy labels, compact vote", ec, compact.ms_per_frame);
  std::cout << "  stray-class vertices: " << stray_class_vertices(compact.mesh) << "\n";
  EXPECT_GE(eb.miou, 0.90);  // issue 3 figure
  EXPECT_GE(ec.miou, 0.80);
}

INSTANTIATE_TEST_SUITE_P(Tsdf, SyntheticQuality, ::testing::Values("grouped", "projective"));

TEST(TumSanity, FusedMeshIsFiniteBoundedAndMostlyClosed) {
  SEMAP_REQUIRE_DATA(root, "tum_fr1_rpy");
  TsdfConfig cfg;
  cfg.voxel_size = 0.02;
  const FuseResult r = fuse_dataset(root, cfg, false, kTumFrames, false);
  const TriangleMesh& mesh = r.mesh;
  ASSERT_GT(mesh.triangles.size(), 10000u);
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(1e9f), hi = -lo;
  for (const auto& p : mesh.vertices.points) {
    ASSERT_TRUE(p.allFinite());
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Eigen::Vector3f extent = hi - lo;
  // Boundary edges (used by one triangle): a fused, mostly closed surface has few.
  std::map<std::pair<uint32_t, uint32_t>, int> edges;
  for (const auto& t : mesh.triangles)
    for (int i = 0; i < 3; ++i) ++edges[{std::min(t[i], t[(i + 1) % 3]), std::max(t[i], t[(i + 1) % 3])}];
  size_t boundary = 0, non_manifold = 0;
  for (const auto& [e, n] : edges) boundary += n == 1, non_manifold += n > 2;
  const double boundary_fraction = static_cast<double>(boundary) / edges.size();
  std::cout << "tum_fr1_rpy " << kTumFrames << " frames: " << mesh.vertices.size() << " vertices, "
            << mesh.triangles.size() << " triangles, extent " << extent.transpose() << " m, boundary edges "
            << boundary_fraction * 100 << " %, non-manifold " << non_manifold << ", " << r.ms_per_frame
            << " ms/frame\n";
  EXPECT_GT(extent.maxCoeff(), 1.0f);
  EXPECT_LT(extent.maxCoeff(), 10.0f);
  // The border of the seen region and small unobserved gaps (measured 8.8 % at 60 frames).
  EXPECT_LT(boundary_fraction, 0.15);
  EXPECT_EQ(non_manifold, 0u);
}

}  // namespace
}  // namespace semap
