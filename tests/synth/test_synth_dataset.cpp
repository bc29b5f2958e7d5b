// The written synthetic dataset: layout, readers, label/gt-point consistency, CLI.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <numeric>
#include <set>
#include <sstream>

#include "semap/core/labels.hpp"
#include "core/progress.hpp"
#include "semap/io/dataset.hpp"
#include "io/image_io.hpp"
#include "semap/io/ply_io.hpp"
#include "semap/io/trajectory_io.hpp"
#include "synth/synth_config.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

namespace fs = std::filesystem;

int count_entries(const fs::path& list) {
  std::ifstream in(list);
  std::string line;
  int n = 0;
  while (std::getline(in, line))
    if (!line.empty() && line[0] != '#') ++n;
  return n;
}

TEST(SynthDataset, WritesCompleteLayoutWithConsistentLabelsAndGtPoints) {
  Progress::set_mode(-1);
  test::TempDir tmp("semap_synth");
  SynthConfig cfg;
  cfg.frames = 40;
  cfg.width = 320;
  cfg.height = 240;
  cfg.seed = 3;
  cfg.seg_noise = 0.2;
  const fs::path d = tmp / "ds";
  const SynthStats stats = generate_dataset(cfg, d);
  EXPECT_GT(stats.render_fps, 0);
  EXPECT_EQ(stats.objects, 12u);
  for (const char* f : {"dataset.yaml", "rgb.txt", "depth.txt", "label.txt", "instance.txt", "groundtruth.txt",
                        "scene.json", "gt_points.ply", "label_noisy.txt", "instance_noisy.txt"})
    EXPECT_TRUE(fs::exists(d / f)) << f;
  for (const char* f : {"rgb.txt", "depth.txt", "label.txt", "instance.txt", "label_noisy.txt", "instance_noisy.txt"})
    EXPECT_EQ(count_entries(d / f), 40) << f;
  for (const char* sub : {"rgb", "depth", "label", "instance", "label_noisy", "instance_noisy"})
    EXPECT_TRUE(fs::exists(d / sub / "000039.png")) << sub;
  // No temporary folder is left beside it.
  for (const auto& e : fs::directory_iterator(tmp.path())) EXPECT_EQ(e.path().filename(), "ds");

  // The io reader opens it with the right camera and frames.
  const auto reader = open_dataset(d);
  EXPECT_EQ(reader->format(), "synthetic");
  ASSERT_EQ(reader->size(), 40u);
  EXPECT_DOUBLE_EQ(reader->camera().depth.fx, 262.5);
  EXPECT_DOUBLE_EQ(reader->camera().depth.cx, 159.5);
  EXPECT_DOUBLE_EQ(reader->camera().depth_scale, 5000.0);
  EXPECT_TRUE(reader->has_label_ground_truth());
  const Frame f0 = reader->load(0);
  EXPECT_EQ(f0.rgb.type(), CV_8UC3);
  EXPECT_EQ(f0.depth.type(), CV_32FC1);
  EXPECT_EQ(f0.labels.cols, 320);

  // scene.json: every object with id, class, class id and an oriented box.
  std::ifstream js(d / "scene.json");
  const nlohmann::json scene = nlohmann::json::parse(js);
  ASSERT_EQ(scene["objects"].size(), 12u);
  for (const auto& o : scene["objects"]) {
    EXPECT_GT(o["instance_id"].get<int>(), 0);
    EXPECT_EQ(class_from_name(o["class"].get<std::string>()).value(), o["class_id"].get<int>());
    EXPECT_EQ(o["obb"]["center"].size(), 3u);
    EXPECT_EQ(o["obb"]["extent"].size(), 3u);
    EXPECT_EQ(o["obb"]["rotation"].size(), 9u);
  }

  // gt_points.ply: every point was observed and its label/instance agree with the label images.
  const TriangleMesh gt = read_ply(d / "gt_points.ply");
  const PointCloud& pts = gt.vertices;
  ASSERT_GT(pts.size(), 100000u);
  ASSERT_TRUE(pts.has_labels() && pts.has_instances() && pts.has_colours() && pts.has_normals());
  const Trajectory traj = read_tum_trajectory(d / "groundtruth.txt");
  ASSERT_EQ(traj.size(), 40u);
  const PinholeIntrinsics K = reader->camera().depth;
  std::vector<uint8_t> seen(pts.size(), 0);
  size_t visible = 0, label_ok = 0, instance_ok = 0;
  std::set<uint32_t> instances_in_points;
  for (size_t i = 0; i < 40; ++i) {
    const Frame f = reader->load(i);
    const Eigen::Isometry3f T_cw = traj[i].T_world_camera.inverse().cast<float>();
    for (size_t k = 0; k < pts.size(); ++k) {
      const Eigen::Vector3f pc = T_cw * pts.points[k];
      if (pc.z() < 0.05f) continue;
      const int u = static_cast<int>(std::lround(K.fx * pc.x() / pc.z() + K.cx));
      const int v = static_cast<int>(std::lround(K.fy * pc.y() / pc.z() + K.cy));
      if (u < 0 || v < 0 || u >= K.width || v >= K.height) continue;
      const float z = f.depth.at<float>(v, u);
      if (!(z > 0) || std::abs(z - pc.z()) > 0.015f) continue;
      if ((T_cw.linear() * pts.normals[k]).dot(pc) >= 0.f) continue;  // faces away from this camera
      seen[k] = 1;
      ++visible;
      label_ok += f.labels.at<uint8_t>(v, u) == pts.labels[k];
      instance_ok += f.instances.at<uint16_t>(v, u) == pts.instances[k];
    }
  }
  for (size_t k = 0; k < pts.size(); ++k) instances_in_points.insert(pts.instances[k]);
  const double seen_fraction = std::accumulate(seen.begin(), seen.end(), 0.0) / pts.size();
  EXPECT_GT(seen_fraction, 0.995) << "gt_points.ply keeps only observed, camera-facing points";
  EXPECT_GT(static_cast<double>(label_ok) / visible, 0.99);
  EXPECT_GT(static_cast<double>(instance_ok) / visible, 0.99);
  EXPECT_EQ(instances_in_points.size(), 13u) << "stuff + 12 objects all observed";

  // A second run into the same folder replaces it; a bad config leaves nothing behind.
  SynthConfig bad = cfg;
  bad.objects = 1000;
  EXPECT_THROW(generate_dataset(bad, tmp / "bad"), std::exception);
  EXPECT_FALSE(fs::exists(tmp / "bad"));
  // A non-empty folder that is not a dataset is never overwritten.
  test::write_text(tmp / "precious" / "notes.txt", "keep me");
  SynthConfig tiny = cfg;
  tiny.frames = 2;
  EXPECT_THROW(generate_dataset(tiny, tmp / "precious"), std::exception);
  EXPECT_TRUE(fs::exists(tmp / "precious" / "notes.txt"));
}

TEST(SynthDataset, DepthNoiseDatasetDiffersFromCleanButStaysClose) {
  Progress::set_mode(-1);
  test::TempDir tmp("semap_synth_noise");
  SynthConfig cfg;
  cfg.frames = 4;
  cfg.width = 160;
  cfg.height = 120;
  cfg.gt_point_spacing = 0.03;
  generate_dataset(cfg, tmp / "clean");
  cfg.depth_noise = true;
  generate_dataset(cfg, tmp / "noisy");
  const cv::Mat clean = read_depth_image(tmp / "clean" / "depth" / "000002.png", 5000.0);
  const cv::Mat noisy = read_depth_image(tmp / "noisy" / "depth" / "000002.png", 5000.0);
  int both = 0, missing = 0, differ = 0;
  double max_err = 0;
  for (int v = 0; v < clean.rows; ++v)
    for (int u = 0; u < clean.cols; ++u) {
      const float c = clean.at<float>(v, u), n = noisy.at<float>(v, u);
      if (c > 0 && n == 0) ++missing;
      if (c > 0 && n > 0) {
        ++both;
        differ += c != n;
        max_err = std::max<double>(max_err, std::abs(c - n));
      }
    }
  EXPECT_GT(both, 0.8 * clean.total());
  EXPECT_GT(missing, 0);
  EXPECT_GT(differ, 0.5 * both);
  EXPECT_LT(max_err, 0.2);
}

TEST(SynthCli, SemapSynthWritesACompleteDataset) {
  const fs::path exe = test::semap_executable();
  ASSERT_TRUE(fs::exists(exe)) << "build the semap target first: " << exe;
  test::TempDir tmp("semap_synth_cli");
  const fs::path d = tmp / "D";
  const auto r = test::run_command(exe.string() + " synth --out " + d.string() + " --frames 60 --seed 1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("frames/s"), std::string::npos) << r.output;
  const auto reader = open_dataset(d);
  EXPECT_EQ(reader->size(), 60u);
  EXPECT_TRUE(reader->has_ground_truth());
  EXPECT_EQ(read_tum_trajectory(d / "groundtruth.txt").size(), 60u);
  EXPECT_GT(read_ply(d / "gt_points.ply").vertices.size(), 100000u);
  const Frame f = reader->load(59);
  EXPECT_EQ(f.rgb.cols, 640);
  EXPECT_EQ(f.depth.rows, 480);
  // Bad input: one clear error line, non-zero exit.
  const auto bad = test::run_command(exe.string() + " synth --out " + (tmp / "E").string() + " --frames 0");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.output.find("frames"), std::string::npos) << bad.output;
  EXPECT_FALSE(fs::exists(tmp / "E"));
}

}  // namespace
}  // namespace semap
