// `semap eval ...` end to end: JSON output parses and carries the expected figures.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "semap/core/pose.hpp"
#include "semap/io/ply_io.hpp"
#include "semap/io/trajectory_io.hpp"
#include "eval/cli_json.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

using test::exe;
using test::run_json;


Trajectory circle_trajectory() {
  Trajectory t;
  for (int i = 0; i < 120; ++i) {
    const double a = 0.05 * i;
    StampedPose p;
    p.timestamp = 100.0 + i / 30.0;
    p.T_world_camera = pose_from_tq({std::cos(a), std::sin(a), 0.1 * a},
                                    Eigen::Quaterniond(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ())));
    t.push_back(p);
  }
  return t;
}

TEST(EvalCli, AteJsonOfTrajectoryAgainstItselfIsZero) {
  test::TempDir dir("semap_eval_cli");
  write_tum_trajectory(dir / "gt.txt", circle_trajectory());
  const std::string gt = (dir / "gt.txt").string();
  const auto j = run_json("eval ate --gt " + gt + " --est " + gt + " --json");
  ASSERT_TRUE(j.contains("ate"));
  EXPECT_LT(j["ate"]["rmse_m"].get<double>(), 1e-9);
  EXPECT_EQ(j["ate"]["matched"].get<int>(), 120);
  EXPECT_LT(j["rpe"]["trans_rmse_m_per_s"].get<double>(), 1e-9);
  EXPECT_GT(j["rpe"]["pairs"].get<int>(), 0);

  // Offset copy: the table names the metric and the figure.
  Trajectory est = circle_trajectory();
  for (size_t i = 0; i < est.size(); ++i) est[i].T_world_camera.translation().z() += (i % 2 ? 0.02 : -0.02);
  write_tum_trajectory(dir / "est.txt", est);
  const auto table = test::run_command(exe() + " eval ate --gt " + gt + " --est " + (dir / "est.txt").string());
  EXPECT_EQ(table.exit_code, 0) << table.output;
  EXPECT_NE(table.output.find("ATE rmse [m]"), std::string::npos) << table.output;
  const auto j2 = run_json("eval ate --gt " + gt + " --est " + (dir / "est.txt").string() + " --json");
  EXPECT_NEAR(j2["ate"]["rmse_m"].get<double>(), 0.02, 1e-3);
}

TEST(EvalCli, ErrorsNameTheFile) {
  test::TempDir dir("semap_eval_cli");
  write_tum_trajectory(dir / "gt.txt", circle_trajectory());
  const auto r = test::run_command(exe() + " eval ate --gt " + (dir / "gt.txt").string() + " --est " +
                                   (dir / "nope.txt").string() + " --json");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("nope.txt"), std::string::npos) << r.output;
  test::write_text(dir / "bad.txt", "1.0 0 0 0 0 0 0 1\n2.0 0 0 zero 0 0 0 1\n");
  const auto bad = test::run_command(exe() + " eval ate --gt " + (dir / "gt.txt").string() + " --est " +
                                     (dir / "bad.txt").string());
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.output.find("bad.txt"), std::string::npos) << bad.output;
  const auto sem = test::run_command(exe() + " eval semantic --gt " + (dir / "missing.ply").string() + " --map " +
                                     (dir / "missing.ply").string());
  EXPECT_NE(sem.exit_code, 0);
  EXPECT_NE(sem.output.find("missing.ply"), std::string::npos) << sem.output;
}

TEST(EvalCli, SemanticAndObjectsJson) {
  test::TempDir dir("semap_eval_cli");
  PointCloud gt;
  for (int i = 0; i < 60; ++i)
    for (int k = 0; k < 60; ++k) {
      gt.points.emplace_back(0.01f * i + 0.003f, 0.01f * k + 0.007f, 0.5f);
      gt.labels.push_back(i < 30 ? id(Label::kTable) : id(Label::kChair));
      gt.instances.push_back(i < 30 ? 1 : 2);
    }
  write_ply(dir / "gt_points.ply", gt);
  const std::string gt_path = (dir / "gt_points.ply").string();
  const auto s = run_json("eval semantic --gt " + gt_path + " --map " + gt_path + " --json --max-dist 0.03");
  EXPECT_DOUBLE_EQ(s["miou"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(s["completeness"].get<double>(), 1.0);
  EXPECT_EQ(s["classes"].size(), 2u);

  std::filesystem::create_directories(dir / "map" / "objects");
  nlohmann::json objects = nlohmann::json::array();
  for (uint32_t inst : {1u, 2u}) {
    PointCloud o;
    for (size_t k = 0; k < gt.size(); ++k)
      if (gt.instances[k] == inst) o.points.push_back(gt.points[k]);
    write_ply(dir / "map" / "objects" / (std::to_string(inst) + ".ply"), o);
    objects.push_back({{"id", inst}, {"class", inst == 1 ? "table" : "chair"}, {"point_count", o.size()},
                       {"points_file", "objects/" + std::to_string(inst) + ".ply"}});
  }
  test::write_text(dir / "map" / "objects.json", nlohmann::json({{"objects", objects}}).dump());
  const auto o = run_json("eval objects --gt " + gt_path + " --map " + (dir / "map" / "objects.json").string() +
                          " --json");
  EXPECT_DOUBLE_EQ(o["wov"].get<double>(), 1.0);
  EXPECT_EQ(o["gt_objects"].get<int>(), 2);
  EXPECT_DOUBLE_EQ(o["matches"][1]["recall"].get<double>(), 1.0);
}

}  // namespace
}  // namespace semap
