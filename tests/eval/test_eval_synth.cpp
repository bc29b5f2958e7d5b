// The metrics on the synthetic world's own ground truth (semap synth): everything perfect.
#include <gtest/gtest.h>

#include <map>
#include <nlohmann/json.hpp>

#include "semap/eval/object_metrics.hpp"
#include "semap/io/ply_io.hpp"
#include "eval/cli_json.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

using test::exe;
using test::run_json;


TEST(EvalSynth, GroundTruthAgainstItself) {
  test::TempDir dir("semap_eval_synth");
  const auto data = dir / "synth";
  const auto synth = test::run_command(exe() + " synth --out '" + data.string() + "' --frames 60 --seed 1");
  ASSERT_EQ(synth.exit_code, 0) << synth.output;

  const std::string gt_traj = (data / "groundtruth.txt").string();
  const auto ate = run_json("eval ate --gt " + gt_traj + " --est " + gt_traj + " --json");
  EXPECT_EQ(ate["ate"]["matched"].get<int>(), 60);
  EXPECT_LT(ate["ate"]["rmse_m"].get<double>(), 1e-9);

  const std::string gt_points = (data / "gt_points.ply").string();
  const auto sem = run_json("eval semantic --gt " + gt_points + " --map " + gt_points + " --json");
  EXPECT_DOUBLE_EQ(sem["miou"].get<double>(), 1.0);
  EXPECT_GE(sem["classes"].size(), 8u);
  EXPECT_DOUBLE_EQ(sem["completeness"].get<double>(), 1.0);

  // objects.json from the GT instances -> WOv 1 against gt_points.ply, and the same count per
  // class as scene.json.
  const auto objects = gt_objects_from_points(read_ply(data / "gt_points.ply").vertices);
  ASSERT_GE(objects.size(), 5u);
  std::filesystem::create_directories(dir / "map" / "objects");
  nlohmann::json list = nlohmann::json::array();
  for (const auto& o : objects) {
    PointCloud cloud;
    cloud.points = o.points;
    write_ply(dir / "map" / "objects" / (std::to_string(o.id) + ".ply"), cloud);
    list.push_back({{"id", o.id}, {"class_id", o.class_id}, {"point_count", o.points.size()},
                    {"points_file", "objects/" + std::to_string(o.id) + ".ply"}});
  }
  test::write_text(dir / "map" / "objects.json", nlohmann::json({{"objects", list}}).dump());
  const std::string objects_json = (dir / "map" / "objects.json").string();
  const auto from_points = run_json("eval objects --gt " + gt_points + " --map " + objects_json + " --json");
  EXPECT_DOUBLE_EQ(from_points["wov"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(from_points["matches"][1]["precision"].get<double>(), 1.0);

  const auto from_scene = run_json("eval objects --gt " + (data / "scene.json").string() + " --map " +
                                   objects_json + " --json");
  // Every scene object is observed in 60 frames? Not necessarily: GT counts >= observed.
  EXPECT_GE(from_scene["gt_objects"].get<size_t>(), objects.size());
  for (const auto& c : from_scene["counts"]) EXPECT_GE(c["gt"].get<int>(), c["map"].get<int>()) << c.dump();
  // Box shells vs observed surfaces: a real but imperfect overlap.
  EXPECT_GT(from_scene["wov"].get<double>(), 0.2);
}

}  // namespace
}  // namespace semap
