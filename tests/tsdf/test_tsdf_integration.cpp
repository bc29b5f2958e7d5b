// Integration, meshing, determinism and persistence on an analytic scene rendered here
// (sphere + wall + floor, exact depth), for both integrators.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>

#include "analytic_scene.hpp"
#include "semap/core/error.hpp"
#include "test_support.hpp"
#include "semap/io/ply_io.hpp"
#include "tsdf/map_io.hpp"
#include "tsdf/semantic_tsdf.hpp"

namespace semap {
namespace {

using test::AnalyticScene;

struct Rendered {
  std::vector<IntegrationInput> frames;
};

const Rendered& rendered_scene() {
  static const Rendered r = [] {
    Rendered out;
    const AnalyticScene scene;
    const PinholeIntrinsics K = AnalyticScene::intrinsics();
    for (const Pose& T : AnalyticScene::poses(12)) {
      IntegrationInput in;
      scene.render(K, T, in.depth, in.labels);
      in.intrinsics = K;
      in.T_world_camera = T;
      in.colour = cv::Mat(in.depth.size(), CV_8UC3, cv::Scalar(10, 20, 30));
      out.frames.push_back(in);
    }
    return out;
  }();
  return r;
}

TsdfConfig config_for(const std::string& integrator, int threads = 2) {
  TsdfConfig c;
  c.voxel_size = 0.02;
  c.integrator = *enum_value(kIntegratorNames, integrator);
  c.threads = threads;
  c.bayes_layer = true;
  c.colour_layer = true;
  return c;
}

SemanticTsdf fuse(const TsdfConfig& c, size_t n_frames = 12) {
  SemanticTsdf tsdf(c);
  const Rendered& r = rendered_scene();
  for (size_t i = 0; i < std::min(n_frames, r.frames.size()); ++i) tsdf.integrate(r.frames[i]);
  return tsdf;
}

struct MeshQuality {
  double mean_distance = 0, p95_distance = 0, label_accuracy = 0, labelled_fraction = 0;
  size_t vertices = 0;
};

MeshQuality measure(const TriangleMesh& mesh) {
  const AnalyticScene scene;
  MeshQuality q;
  std::vector<double> d;
  size_t correct = 0, labelled = 0;
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Eigen::Vector3d p = mesh.vertices.points[i].cast<double>();
    d.push_back(scene.distance(p));
    if (mesh.vertices.labels[i] == 0) continue;  // too little label evidence: shown unlabelled
    ++labelled;
    correct += mesh.vertices.labels[i] == scene.label_at(p);
  }
  q.vertices = d.size();
  if (d.empty()) return q;
  for (double x : d) q.mean_distance += x;
  q.mean_distance /= d.size();
  std::sort(d.begin(), d.end());
  q.p95_distance = d[d.size() * 95 / 100];
  q.label_accuracy = static_cast<double>(correct) / std::max<size_t>(labelled, 1);
  q.labelled_fraction = static_cast<double>(labelled) / d.size();
  return q;
}

class BothIntegrators : public ::testing::TestWithParam<std::string> {};

TEST_P(BothIntegrators, MeshLiesOnTheTrueSurfaceWithTheRightLabels) {
  SemanticTsdf tsdf = fuse(config_for(GetParam()));
  const TriangleMesh mesh = tsdf.extract_mesh();
  const MeshQuality q = measure(mesh);
  std::cout << GetParam() << ": vertices " << q.vertices << " triangles " << mesh.triangles.size() << " mean "
            << q.mean_distance * 1000 << " mm p95 " << q.p95_distance * 1000 << " mm labels " << q.label_accuracy << " labelled " << q.labelled_fraction
            << " blocks " << tsdf.map().num_blocks() << "\n";
  EXPECT_GT(q.vertices, 20000u);
  EXPECT_LT(q.mean_distance, 0.003);
  EXPECT_LT(q.p95_distance, 0.008);
  EXPECT_GT(q.label_accuracy, 0.97);
  EXPECT_GT(q.labelled_fraction, 0.85);
  for (const auto& p : mesh.vertices.points) ASSERT_TRUE(p.allFinite());
  // Triangle normals point towards free space (the cameras sit at z ~ 0, surfaces beyond).
  size_t towards = 0;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3f& a = mesh.vertices.points[t[0]];
    const Eigen::Vector3f n = (mesh.vertices.points[t[1]] - a).cross(mesh.vertices.points[t[2]] - a);
    towards += n.dot(-a) > 0;
  }
  EXPECT_GT(towards, mesh.triangles.size() * 9 / 10);
  // Welded: vertices shared by several triangles (a closed sheet has ~2 triangles per vertex).
  EXPECT_GT(static_cast<double>(mesh.triangles.size()) / mesh.vertices.size(), 1.7);
  // Colour layer: RGB (30, 20, 10) everywhere.
  tsdf.map();
  EXPECT_EQ(tsdf.map().bytes_per_voxel(), 4u + 1u + 8u + 3u);
}

TEST_P(BothIntegrators, DeterministicAcrossRunsAndThreadCounts) {
  SemanticTsdf a = fuse(config_for(GetParam(), 1), 4);
  SemanticTsdf b = fuse(config_for(GetParam(), 1), 4);
  SemanticTsdf c = fuse(config_for(GetParam(), 2), 4);
  EXPECT_TRUE(a.map() == b.map());
  EXPECT_TRUE(a.map() == c.map());
}

// Per-pixel class probabilities (a semantic network's softmax) reach the Bayes layer: 0.7 on
// the rendered label, the rest spread over the other classes. The grouped integrator sums them
// per group across its strips of rows; a group mixed up there would mislabel its surface.
TEST_P(BothIntegrators, PerPixelProbabilitiesFuseIntoTheBayesLayer) {
  auto fuse_probabilities = [](int threads) {
    SemanticTsdf tsdf(config_for(GetParam(), threads));
    for (IntegrationInput in : rendered_scene().frames) {
      in.probabilities = cv::Mat(in.depth.size(), CV_32FC(kNumClasses));
      for (int v = 0; v < in.depth.rows; ++v)
        for (int u = 0; u < in.depth.cols; ++u) {
          float* p = in.probabilities.ptr<float>(v) + static_cast<size_t>(u) * kNumClasses;
          std::fill(p, p + kNumClasses, 0.3f / (kNumClasses - 1));
          p[in.labels.at<uint8_t>(v, u)] = 0.7f;
        }
      tsdf.integrate(in);
    }
    return tsdf;
  };
  SemanticTsdf one = fuse_probabilities(1), two = fuse_probabilities(2);
  EXPECT_TRUE(one.map() == two.map());
  const MeshQuality q = measure(two.extract_mesh());
  std::cout << GetParam() << ": labels " << q.label_accuracy << " labelled " << q.labelled_fraction << "\n";
  EXPECT_GT(q.label_accuracy, 0.97);
  EXPECT_GT(q.labelled_fraction, 0.85);
}

TEST_P(BothIntegrators, IncrementalMeshEqualsFullRemesh) {
  TsdfConfig cfg = config_for(GetParam());
  SemanticTsdf tsdf(cfg);
  const Rendered& r = rendered_scene();
  MeshExtractor incremental;
  size_t last_blocks = 0;
  for (size_t i = 0; i < 6; ++i) {
    tsdf.integrate(r.frames[i]);
    incremental.extract(tsdf.map());
    last_blocks = incremental.last_remeshed_blocks();
  }
  EXPECT_GT(last_blocks, 0u);
  // A frame touching nothing new re-meshes nothing.
  const TriangleMesh inc = incremental.extract(tsdf.map());
  EXPECT_EQ(incremental.last_remeshed_blocks(), 0u);
  const TriangleMesh full = MeshExtractor().extract_full(tsdf.map());
  ASSERT_EQ(inc.vertices.size(), full.vertices.size());
  ASSERT_EQ(inc.triangles.size(), full.triangles.size());
  EXPECT_EQ(inc.vertices.points, full.vertices.points);
  EXPECT_EQ(inc.vertices.labels, full.vertices.labels);
  EXPECT_EQ(inc.triangles, full.triangles);
}

// A wall 4 m away, measured by frames whose depth lies 8 cm (3 sigma of Kinect v1 at 4 m) before
// or behind it. The fused surface lies between the measurements, beyond a fixed 2-voxel label
// band of most frames; the band that widens with the depth noise labels all of it.
TEST_P(BothIntegrators, FarNoisyDepthStillLabelsTheFusedSurface) {
  const PinholeIntrinsics K = AnalyticScene::intrinsics();
  const auto labelled_share = [&](double band_sigmas) {
    TsdfConfig c = config_for(GetParam());
    c.label_band_sigmas = band_sigmas;
    SemanticTsdf tsdf(c);
    for (int i = 0; i < 8; ++i) {
      IntegrationInput in;
      in.intrinsics = K;
      in.T_world_camera = Pose::Identity();
      in.depth = cv::Mat(K.height, K.width, CV_32FC1, cv::Scalar(i % 2 == 0 ? 4.08f : 3.92f));
      in.labels = cv::Mat(K.height, K.width, CV_8UC1, cv::Scalar(id(Label::kWall)));
      tsdf.integrate(in);
    }
    const TriangleMesh mesh = tsdf.extract_mesh();
    size_t labelled = 0;
    for (ClassId l : mesh.vertices.labels) labelled += l == id(Label::kWall);
    return static_cast<double>(labelled) / std::max<size_t>(mesh.vertices.size(), 1);
  };
  const double widened = labelled_share(TsdfConfig{}.label_band_sigmas), fixed = labelled_share(0.0);
  std::cout << GetParam() << ": wall at 4 m labelled " << widened << " (fixed 2-voxel band " << fixed << ")\n";
  EXPECT_GT(widened, 0.95);
  EXPECT_LT(fixed, 0.85);  // measured 0.72-0.73
}

INSTANTIATE_TEST_SUITE_P(Tsdf, BothIntegrators, ::testing::Values("grouped", "projective"));

TEST(MapIo, SaveLoadIsExactAndCorruptionIsAnError) {
  SemanticTsdf tsdf = fuse(config_for("grouped"), 3);
  test::TempDir dir("tsdf_io");
  const auto path = dir / "map.semap";
  tsdf.save(path);
  const TsdfMap loaded = load_map(path);
  EXPECT_TRUE(loaded == tsdf.map());
  EXPECT_EQ(loaded.num_blocks(), tsdf.map().num_blocks());
  // Truncated.
  const auto size = std::filesystem::file_size(path);
  std::filesystem::copy_file(path, dir / "truncated.semap");
  std::filesystem::resize_file(dir / "truncated.semap", size / 2);
  EXPECT_THROW(load_map(dir / "truncated.semap"), Error);
  // One flipped byte in the payload.
  std::filesystem::copy_file(path, dir / "corrupt.semap");
  {
    std::fstream f(dir / "corrupt.semap", std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(size / 3));
    char c;
    f.read(&c, 1);
    f.seekp(static_cast<std::streamoff>(size / 3));
    c ^= 0x10;
    f.write(&c, 1);
  }
  try {
    load_map(dir / "corrupt.semap");
    FAIL() << "corrupt map loaded";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("corrupt.semap"), std::string::npos) << e.what();
  }
  // Wrong version.
  std::filesystem::copy_file(path, dir / "version.semap");
  {
    std::fstream f(dir / "version.semap", std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(8);
    const uint32_t v = 99;
    f.write(reinterpret_cast<const char*>(&v), 4);
  }
  EXPECT_THROW(load_map(dir / "version.semap"), Error);
  EXPECT_THROW(load_map(dir / "missing.semap"), Error);
}

TEST(MeshPly, WrittenMeshCarriesColoursAndLabels) {
  TsdfConfig c = config_for("projective");
  c.mesh_colour = MeshColour::class_palette;  // the default is the surface colour; the palette is checked here
  SemanticTsdf tsdf = fuse(c, 3);  // 3 frames: labels need three frames' evidence
  test::TempDir dir("tsdf_ply");
  tsdf.write_mesh(dir / "mesh.ply");
  const TriangleMesh back = read_ply(dir / "mesh.ply");
  const TriangleMesh mesh = tsdf.extract_mesh();
  ASSERT_EQ(back.vertices.size(), mesh.vertices.size());
  ASSERT_EQ(back.triangles.size(), mesh.triangles.size());
  ASSERT_TRUE(back.vertices.has_labels());
  ASSERT_TRUE(back.vertices.has_colours());
  EXPECT_EQ(back.vertices.labels, mesh.vertices.labels);
  size_t chair = 0;
  for (size_t i = 0; i < back.vertices.size(); ++i)
    if (back.vertices.labels[i] == id(Label::kChair)) {
      ++chair;
      EXPECT_EQ(back.vertices.colours[i], class_colour(id(Label::kChair)));
    }
  EXPECT_GT(chair, 1000u);
}

TEST(Integration, InvalidDepthIsSkippedAndBadInputRejected) {
  TsdfConfig cfg = config_for("grouped");
  cfg.max_depth = 2.5;
  SemanticTsdf tsdf(cfg);
  IntegrationInput in = rendered_scene().frames[0];
  in.depth = in.depth.clone();
  in.depth.at<float>(10, 10) = std::numeric_limits<float>::quiet_NaN();
  in.depth.at<float>(11, 10) = 0.0f;
  in.depth.at<float>(12, 10) = -1.0f;
  tsdf.integrate(in);
  // Only the sphere (< 2.5 m) survives the range cut: no vertex beyond 2.5 m + truncation.
  const TriangleMesh mesh = tsdf.extract_mesh();
  ASSERT_FALSE(mesh.vertices.empty());
  for (const auto& p : mesh.vertices.points) {
    ASSERT_TRUE(p.allFinite());
    EXPECT_LT(p.z(), 2.5 + cfg.truncation() + 0.05);  // frame 0 looks along +z
  }
  IntegrationInput bad = in;
  bad.depth = cv::Mat(10, 10, CV_16UC1);
  EXPECT_THROW(tsdf.integrate(bad), Error);
  bad = in;
  bad.labels = cv::Mat(5, 5, CV_8UC1);
  EXPECT_THROW(tsdf.integrate(bad), Error);
  // An unknown integrator name cannot reach make_integrator: it is an enum (the config loader refuses the name).
  EXPECT_FALSE(enum_value(kIntegratorNames, "nope"));
}

TEST(Integration, DropDistanceFreesFarBlocks) {
  TsdfConfig cfg = config_for("projective");
  cfg.drop_distance = 2.2;
  SemanticTsdf tsdf(cfg);
  tsdf.integrate(rendered_scene().frames[0]);
  const Eigen::Vector3f cam = rendered_scene().frames[0].T_world_camera.translation().cast<float>();
  for (const auto& b : tsdf.map().blocks()) {
    const Eigen::Vector3f c = (b->index.cast<float>().array() + 0.5f) * tsdf.map().block_size();
    EXPECT_LE((c - cam).norm(), 2.2f);
  }
}

}  // namespace
}  // namespace semap
