// `semap demo` (the README's main job: 240 synthetic frames, tracked poses, 20 % label flicker)
// against the figures the README states, with a margin, and the claim that chose the default
// label rule: the Bayesian layer (METHODS A6) beats the compact vote (B6) under flicker.
// Heavy (three runs on one rendered world, ~2-4 min on 2 cores); CI runs it (scripts/test.sh, heavy subset).
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "test_support.hpp"

namespace semap::test {
namespace {

// Bounds with a margin over the figures measured by this test (2026-12-04, the closing printf):
// ATE 0.16 cm, mIoU 0.943 (compact vote 0.863), WOv 0.882 by surface IoU at 2 cm (issue 17's
// target 0.75; 0.850 before exported points the TSDF labels as another class were left out),
// 12 objects for 12. The voxel-set figure of the same map is 0.639 (0.607 before; 0.582 and 11
// objects while C5's containment test used raw boxes; 0.484 before object points were projected
// onto the fused surface): kept as a floor so that the object points do not drift off the surface.
constexpr double kDemoMaxAteM = 0.01;
constexpr double kDemoMinWov = 0.75;
constexpr double kDemoMinVoxelWov = 0.58;

/// Runs `command` with `config_yaml` (if any) as --config; OUT's report.json, parsed.
nlohmann::json run_with_report(const TempDir& dir, const std::string& name, std::string command,
                               const std::string& config_yaml) {
  if (!config_yaml.empty()) {
    write_text(dir / (name + ".yaml"), config_yaml);
    command += " --config " + shell_quote((dir / (name + ".yaml")).string());
  }
  const CommandResult r = run_command(command);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(dir / name / "report.json");
  return in ? nlohmann::json::parse(in, nullptr, false) : nlohmann::json();
}

/// `semap demo --out DIR/NAME`: generates the synthetic world into DIR/NAME/dataset and maps it.
nlohmann::json run_demo(const TempDir& dir, const std::string& name) {
  return run_with_report(dir, name, shell_quote(semap_executable().string()) + " demo --out " + shell_quote((dir / name).string()), {});
}

/// What `semap demo` runs on its world, as `semap run` on an already generated one (the world is
/// rendered once per test, not once per run: about 12 s each).
nlohmann::json run_demo_world(const TempDir& dir, const std::filesystem::path& dataset, const std::string& name,
                              const std::string& config_yaml) {
  const std::string command = shell_quote(semap_executable().string()) + " run " + shell_quote(dataset.string()) +
                              " --segmenter groundtruth --seg-noise 0.2 --out " + shell_quote((dir / name).string());
  return run_with_report(dir, name, command, config_yaml);
}

double figure(const nlohmann::json& report, const char* section, const char* key) {
  const auto& e = report["evaluation"];
  if (!e.contains(section) || !e[section].contains(key)) return std::nan("");
  return e[section][key].get<double>();
}

TEST(Demo, FiguresOfTheReadmeHoldAndTheBayesianLayerBeatsTheCompactVote) {
  TempDir dir("semap_demo");
  const nlohmann::json bayes = run_demo(dir, "bayes");
  // The label rule compared as fusion alone, every mesh-time label rule (tsdf/label_priors.hpp,
  // on by default) off: they repair either rule's mesh afterwards.
  const std::string no_priors = "tsdf:\n  label_prior_normals: false\n  label_prior_heights: false\n"
                                "  label_prior_regions: false\n  label_prior_segments: false\n"
                                "  label_prior_likely: false\n  label_prior_other: false\n  label_prior_fringes: false\n";
  const nlohmann::json fused = run_demo_world(dir, dir / "bayes" / "dataset", "bayes_no_priors", no_priors);
  const nlohmann::json compact =
      run_demo_world(dir, dir / "bayes" / "dataset", "compact_no_priors", no_priors + "  bayes_layer: false\n");
  ASSERT_TRUE(bayes.is_object() && fused.is_object() && compact.is_object()) << "no report.json";
  const double ate_m = figure(bayes, "ate", "rmse_m"), miou = figure(bayes, "semantic", "miou");
  const double miou_fused = figure(fused, "semantic", "miou"), miou_compact = figure(compact, "semantic", "miou");
  const double wov = figure(bayes, "objects", "wov"), wov_voxel = figure(bayes, "objects", "wov_voxel");
  const int gt_objects = bayes["evaluation"]["objects"]["gt_objects"].get<int>();
  const int map_objects = bayes["evaluation"]["objects"]["map_objects"].get<int>();
  std::printf("[demo] ATE %.2f cm, mIoU %.3f (without label rules: Bayesian %.3f, compact vote %.3f), WOv %.3f "
              "(voxel-set %.3f), objects %d (gt %d)\n",
              ate_m * 100, miou, miou_fused, miou_compact, wov, wov_voxel, map_objects, gt_objects);
  // README: mIoU 0.944 (0.943 Bayesian without any label rule, 0.863 compact). Measured
  // 2026-12-07 after the likely and `other` rules: 0.944 (0.949 before them; 0.943 / 0.863 with
  // every rule off). 0.94 is issue 38's "nothing lost" bound; the smooth segments' small joins
  // had cost 0.016 on the demo's mesh.
  EXPECT_LE(ate_m, kDemoMaxAteM);
  EXPECT_GE(miou, 0.94);
  EXPECT_GE(miou, miou_fused - 0.005) << "the label rules must not cost accuracy on the demo";
  EXPECT_GE(miou_fused - miou_compact, 0.04) << "the default label rule was chosen by this margin";
  EXPECT_GE(wov, kDemoMinWov);
  EXPECT_GE(wov_voxel, kDemoMinVoxelWov);
  EXPECT_LE(std::abs(map_objects - gt_objects), 1);
}

}  // namespace
}  // namespace semap::test
