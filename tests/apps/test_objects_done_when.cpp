// Issue 6 "done when", through the CLI exactly as a user runs it (heavy: ~1-2 min):
//   semap synth --frames 300 --seed 1 --objects 10
//   semap run D --segmenter groundtruth --poses groundtruth
//   semap eval objects --gt D/gt_points.ply --map O/objects.json --json
// -> exact object count per class and WOv >= 0.85 (METHODS.md C6). Measured 2026-12-04: WOv 0.981
// by surface IoU at 2 cm (0.897 by the grid-dependent voxel sets); the bound keeps a margin
// under the measured figure.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "test_support.hpp"

namespace semap::test {
namespace {

TEST(ObjectsDoneWhen, GroundTruthMasksGiveExactCountsAndWov) {
  TempDir dir("semap_objects_done_when");
  const std::string semap = semap_executable().string();
  const auto data = dir / "D", out = dir / "O";
  CommandResult r = run_command(semap + " synth --out " + data.string() + " --frames 300 --seed 1 --objects 10");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run_command(semap + " run " + data.string() + " --segmenter groundtruth --poses groundtruth --out " +
                  out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run_command(semap + " eval objects --gt " + (data / "gt_points.ply").string() + " --map " +
                  (out / "objects.json").string() + " --json 2>/dev/null");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  std::cout << "WOv " << j["wov"] << " (voxel-set " << j["wov_voxel"] << ")\n";
  for (const auto& c : j["counts"]) {
    EXPECT_EQ(c["gt"], c["map"]) << c.dump();
  }
  EXPECT_GE(j["wov"].get<double>(), 0.93);
}

}  // namespace
}  // namespace semap::test
