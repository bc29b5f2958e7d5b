// Merging two saved maps made independently (issue 19): `semap merge A B --out C` relocalises
// B's keyframes into A, verifies that they agree, and fuses B's TSDF, objects and keyframes into
// A's world frame. Checked on a split of a shared sequence against the ground truth with ONE
// alignment of the joint trajectory, and on two different rooms (not merged).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "core/progress.hpp"
#include "semap/core/error.hpp"
#include "semap/eval/trajectory_metrics.hpp"
#include "semap/io/dataset.hpp"
#include "semap/io/ply_io.hpp"
#include "semap/io/trajectory_io.hpp"
#include "semap/mapper.hpp"
#include "semap/pipeline/map_merge.hpp"
#include "sequence_slices.hpp"
#include "synth/synth_config.hpp"
#include "pipeline/resume_support.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

namespace fs = std::filesystem;
using test::file_bytes;
using test::map_recording;

Trajectory concatenated(const Trajectory& a, const Trajectory& b) {
  Trajectory out = a;
  out.insert(out.end(), b.begin(), b.end());
  return out;
}

size_t mesh_vertices(const fs::path& ply) { return read_ply(ply).vertices.points.size(); }

// TUM fr1_rpy frames 0-59 and 40-99, each mapped on its own (its own world frame: its first
// camera), then merged.
TEST(MapMerge, OverlappingRecordingsMappedApartMergeIntoOneWorldFrame) {
  SEMAP_REQUIRE_DATA(tum, "tum_fr1_rpy");
  Progress::set_mode(-1);
  test::TempDir tmp("semap_merge");
  const auto rec1 = test::write_sequence_slice(tum, {.first = 0, .last = 59}, tmp / "rec1");
  const auto rec2 = test::write_sequence_slice(tum, {.first = 40, .last = 99}, tmp / "rec2");
  map_recording(rec1.dir, tmp / "mon");
  map_recording(rec2.dir, tmp / "tue");
  const std::string a_before = file_bytes(tmp / "mon" / "map.semap"), b_before = file_bytes(tmp / "tue" / "map.semap");

  const MapMergeResult r = merge_maps(tmp / "mon", tmp / "tue", tmp / "merged");
  ASSERT_TRUE(r.merged) << r.reason;
  EXPECT_TRUE(file_bytes(tmp / "mon" / "map.semap") == a_before && file_bytes(tmp / "tue" / "map.semap") == b_before)
      << "the inputs are only read";

  // Where the two recordings overlap (frames 40-59) each estimated the same camera poses in
  // its own world: T_a_b must carry B's estimates onto A's (both maps' drift differs a little).
  const Trajectory est1 = read_tum_trajectory(tmp / "mon" / "trajectory.txt");
  const Trajectory est2 = read_tum_trajectory(tmp / "tue" / "trajectory.txt");
  double worst_m = 0, worst_deg = 0;
  for (const StampedPose& p2 : est2)
    for (const StampedPose& p1 : est1)
      if (std::abs(p1.timestamp - p2.timestamp) < 1e-6) {
        const Pose d = p1.T_world_camera.inverse() * r.T_a_b * p2.T_world_camera;
        worst_m = std::max(worst_m, d.translation().norm());
        worst_deg = std::max(worst_deg, rotation_angle(d) * 180 / M_PI);
      }
  const Trajectory gt1 = open_dataset(rec1.dir)->ground_truth(), gt2 = open_dataset(rec2.dir)->ground_truth();
  const Trajectory t1 = read_tum_trajectory(tmp / "merged" / "mon.trajectory.txt");
  const Trajectory t2 = read_tum_trajectory(tmp / "merged" / "tue.trajectory.txt");
  const double ate_joint = compute_ate(concatenated(gt1, gt2), concatenated(t1, t2)).rmse;
  const size_t v1 = mesh_vertices(tmp / "mon" / "mesh.ply"), v = mesh_vertices(tmp / "merged" / "mesh.ply");
  std::printf("[merge] tum 0-59 + 40-99: %zu of %zu keyframes relocalised, %zu agree; overlap frames A vs T_a_b B "
              "within %.2f cm %.2f deg; joint ATE %.2f cm (one alignment); mesh %zu + %zu -> %zu vertices; %.2f s "
              "relocalisation, %.2f s fusion\n",
              r.keyframes_verified, r.keyframes_b, r.keyframes_agreeing, worst_m * 100, worst_deg, ate_joint * 100, v1,
              mesh_vertices(tmp / "tue" / "mesh.ply"), v, r.relocalisation_s, r.fusion_s);
  EXPECT_LT(worst_m, 0.05);
  EXPECT_LT(worst_deg, 3.0);
  EXPECT_LE(ate_joint, 0.05);
  EXPECT_GE(r.keyframes_agreeing, 2u);
  EXPECT_GT(v, v1) << "the merged mesh holds B's surfaces too";

  // The merged map is a complete map: it loads with both recordings' keyframes and merges again.
  EXPECT_EQ(Mapper::load(tmp / "merged" / "map.semap")->stats().resumed_keyframes, r.keyframes_a + r.keyframes_b);
  // Issue 44: a user's file where an output goes (here a trajectory) is never replaced.
  fs::create_directories(tmp / "merged2");
  { std::ofstream(tmp / "merged2" / "tue_2.trajectory.txt") << "mine\n"; }
  EXPECT_THROW(merge_maps(tmp / "merged", tmp / "tue", tmp / "merged2"), Error);
  EXPECT_EQ(file_bytes(tmp / "merged2" / "tue_2.trajectory.txt"), "mine\n");
  EXPECT_FALSE(fs::exists(tmp / "merged2" / "map.semap"));
  fs::remove(tmp / "merged2" / "tue_2.trajectory.txt");
  const MapMergeResult again = merge_maps(tmp / "merged", tmp / "tue", tmp / "merged2");
  ASSERT_TRUE(again.merged) << again.reason;
  EXPECT_TRUE(fs::exists(tmp / "merged2" / "tue_2.trajectory.txt")) << "recording names stay unique";
}

TEST(MapMerge, MapsOfDifferentRoomsAreNotMergedAndNothingIsWritten) {
  Progress::set_mode(-1);
  test::TempDir tmp("semap_merge_apart");
  test::write_two_rooms(tmp.path());
  map_recording(tmp / "room1", tmp / "out1");
  map_recording(tmp / "room2", tmp / "out2");
  const MapMergeResult r = merge_maps(tmp / "out1", tmp / "out2", tmp / "merged");
  EXPECT_FALSE(r.merged);
  EXPECT_NE(r.reason.find("does not relocalise"), std::string::npos) << r.reason;
  EXPECT_FALSE(fs::exists(tmp / "merged" / "map.semap"));
  std::printf("[merge] two rooms: %s\n", r.reason.c_str());

  // The CLI: one line naming the map, exit 1, no output folder content; inputs as outputs refused.
  auto semap_merge = [&](const fs::path& out) {
    return test::run_command(test::shell_quote(test::semap_executable().string()) + " merge " +
                             test::shell_quote((tmp / "out1").string()) + " " + test::shell_quote((tmp / "out2").string()) +
                             " --out " + test::shell_quote(out.string()) + " 2>&1");
  };
  const auto cli = semap_merge(tmp / "cli");
  EXPECT_EQ(cli.exit_code, 1) << cli.output;
  EXPECT_NE(cli.output.find("does not relocalise"), std::string::npos) << cli.output;
  EXPECT_FALSE(fs::exists(tmp / "cli" / "map.semap"));
  const auto same = semap_merge(tmp / "out1");
  EXPECT_EQ(same.exit_code, 1) << same.output;
  EXPECT_NE(same.output.find("is the input"), std::string::npos) << same.output;  // issue 44 wording
}

}  // namespace
}  // namespace semap
