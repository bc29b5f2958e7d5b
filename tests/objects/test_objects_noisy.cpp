// Noisy-segmentation mode (issue 6 "Measured"), like the seed's Tables 1 and 2: objects per
// class for {no optimisation, merge only, delete only, both} and WOv for {mask back-projection,
// supervoxel-guided}. Heavy: it renders a 160-frame sequence and segments its 80 keyframes three
// times (two segmentation modes; duplicating noise).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <iostream>

#include "objects_synth_support.hpp"
#include "test_support.hpp"

using namespace semap;

namespace {

struct KeyframeSegments {
  size_t frame_index;
  std::vector<ObjectSegment> segments;
};

// Uncorrected drift between passes: in every other block of `drift_block` frames the segments
// are placed with T_drift * T_world_camera (as when a loop closure corrected the trajectory but
// not the segments already placed). A shift beyond d_point makes an object seen again in the
// other state fail the C4 overlap test and start a duplicate, which C5 must merge (the redkitchen
// chairs' duplicates were of this kind). drift_block 0: the true poses.
Eigen::Isometry3d drift_between_passes() {
  Eigen::Isometry3d T_drift = Eigen::Isometry3d::Identity();
  T_drift.translation() = Eigen::Vector3d(0.06, 0.0, 0.04);
  T_drift.linear() = Eigen::AngleAxisd(2.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return T_drift;
}

std::vector<KeyframeSegments> segment_sequence(const std::filesystem::path& dataset, const ObjectsConfig& config,
                                               const SegmentationNoiseParams& noise, int frame_step,
                                               size_t drift_block = 0) {
  const auto reader = open_dataset(dataset);
  FrameSegmenter segmenter(config, reader->camera());
  std::vector<KeyframeSegments> out;
  for (size_t i = 0; i < reader->size(); i += frame_step) {
    const Frame frame = reader->load(i);
    const auto [labels, instances] = apply_segmentation_noise(frame.labels, frame.instances, i, noise);
    Pose T_world_camera = *frame.gt_T_world_camera;
    if (drift_block > 0 && (i / drift_block) % 2 == 1) T_world_camera = drift_between_passes() * T_world_camera;
    out.push_back({i, segmenter.segment(frame, test::segmentation_from_labels(labels, instances, 100), T_world_camera)});
  }
  return out;
}

// Same loop as ObjectMapper::process/finish, on precomputed segments.
std::vector<ObjectInstance> map_sequence(const std::vector<KeyframeSegments>& frames, const ObjectsConfig& config) {
  ObjectMap map(config);
  size_t step = 0;
  for (const auto& kf : frames) {
    map.associate(kf.segments, kf.frame_index, ++step);
    if (config.enable_optimisation && step % config.optimise_every == 0) map.optimise(step, false);
  }
  if (config.enable_optimisation && config.final_optimisation && step % config.optimise_every != 0)
    map.optimise(step, true);
  return map.instances();
}

int count_error(const std::map<std::string, int>& got, const std::map<std::string, int>& truth) {
  std::set<std::string> classes;
  for (const auto& [c, n] : got) classes.insert(c);
  for (const auto& [c, n] : truth) classes.insert(c);
  int error = 0;
  for (const auto& c : classes) {
    const int a = got.count(c) ? got.at(c) : 0, b = truth.count(c) ? truth.at(c) : 0;
    error += std::abs(a - b);
  }
  return error;
}

}  // namespace

TEST(ObjectsNoisy, OptimisationAndSupervoxelsImproveNoisyMaps) {
  test::TempDir dir("objects_noisy");
  SynthConfig synth;
  synth.frames = 160;
  synth.seed = 1;
  synth.objects = 10;
  synth.width = 320;
  synth.height = 240;
  generate_dataset(synth, dir.path() / "data");
  const auto gt = test::load_gt_objects(dir.path() / "data");
  const auto truth = test::counts_per_class(gt);
  const size_t truth_total = gt.classes.size();
  if (std::getenv("SEMAP_OBJECTS_DEBUG"))
    for (const auto& [inst, pts] : gt.points) {
      Eigen::Vector3f c = Eigen::Vector3f::Zero();
      for (const auto& p : pts) c += p;
      std::cout << "gt " << inst << " " << class_name(gt.classes.at(inst)) << " points " << pts.size() << " centroid "
                << (c / static_cast<float>(pts.size())).transpose() << "\n";
    }

  SegmentationNoiseParams noise;
  noise.flicker_rate = 0.2;
  noise.miss_rate = 0.1;
  noise.merge_rate = 0.2;
  noise.border_rate = 0.5;
  noise.border_px = 3;
  ObjectsConfig base;
  base.pixel_stride = 1;
  base.optimise_every = 50;
  const int frame_step = 2;

  ObjectsConfig backprojection = base;
  backprojection.segmentation_mode = SegmentationMode::backprojection;
  const auto supervoxel_frames = segment_sequence(dir.path() / "data", base, noise, frame_step);
  const auto backprojection_frames = segment_sequence(dir.path() / "data", backprojection, noise, frame_step);
  // The counts table: the same noise plus what makes duplicates, over-segmentation (an object
  // first seen split starts as two instances) and drift between passes.
  SegmentationNoiseParams duplicating_noise = noise;
  duplicating_noise.split_rate = 0.3;
  const auto duplicating_frames = segment_sequence(dir.path() / "data", base, duplicating_noise, frame_step, 40);

  struct Variant {
    std::string name;
    bool merge, del;
  };
  const std::vector<Variant> variants = {{"no optimisation", false, false}, {"merge only", true, false},
                                         {"delete only", false, true}, {"both", true, true}};
  std::map<std::string, int> errors;
  std::map<std::string, size_t> totals;
  std::set<std::string> classes;
  for (const auto& [c, n] : truth) classes.insert(c);
  std::map<std::string, std::map<std::string, int>> table;
  for (const auto& v : variants) {
    ObjectsConfig c = base;
    c.enable_optimisation = v.merge || v.del;
    c.enable_merge = v.merge;
    c.enable_delete = v.del;
    const auto instances = map_sequence(duplicating_frames, c);
    table[v.name] = test::counts_per_class(instances);
    for (const auto& [cls, n] : table[v.name]) classes.insert(cls);
    errors[v.name] = count_error(table[v.name], truth);
    totals[v.name] = instances.size();
    if (std::getenv("SEMAP_OBJECTS_DEBUG"))
      for (const auto& inst : instances)
        std::cout << v.name << ": id " << inst.id << " " << class_name(inst.class_id()) << " n " << inst.n << " s "
                  << inst.total_associations << " points " << inst.points.size() << " " << state_name(inst.state)
                  << " frames " << inst.first_frame << "-" << inst.last_frame << " centroid "
                  << inst.centroid().transpose() << "\n";
  }
  std::cout << "| variant | ";
  for (const auto& c : classes) std::cout << c << " | ";
  std::cout << "total | count error |\n";
  auto row = [&](const std::string& name, const std::map<std::string, int>& counts, size_t total, int error) {
    std::cout << "| " << name << " | ";
    for (const auto& c : classes) std::cout << (counts.count(c) ? counts.at(c) : 0) << " | ";
    std::cout << total << " | " << error << " |\n";
  };
  row("ground truth", truth, gt.classes.size(), 0);
  for (const auto& v : variants) row(v.name, table[v.name], totals[v.name], errors[v.name]);

  const double wov_supervoxel = test::weighted_overlap(gt, map_sequence(supervoxel_frames, base));
  const double wov_backprojection = test::weighted_overlap(gt, map_sequence(backprojection_frames, base));
  ObjectsConfig no_opt = base;
  no_opt.enable_optimisation = false;
  const double wov_supervoxel_noopt = test::weighted_overlap(gt, map_sequence(supervoxel_frames, no_opt));
  const double wov_backprojection_noopt = test::weighted_overlap(gt, map_sequence(backprojection_frames, no_opt));
  std::cout << "WOv (both optimisations): mask back-projection " << wov_backprojection << ", supervoxel-guided "
            << wov_supervoxel << "\nWOv (no optimisation): mask back-projection " << wov_backprojection_noopt
            << ", supervoxel-guided " << wov_supervoxel_noopt << "\n";

  // Measured (160 frames, step 2; counts with 30 % splits and a 6 cm / 2 deg drift every other
  // 40 frames): no optimisation 42 instances for 10 objects (count error 32), merge only 39
  // (29), delete only 13 (3: a second bookcase, chair and sofa, one per drifted pass), both 10
  // (2). Deletion removes the split fragments (seen a few times, C5 deletion rule); merging
  // removes the drift duplicates (STABLE, co-associated, inside each other's box, same class).
  // Its cost: the two touching chairs, merged by the noise's mask merges in some frames, end as
  // one. WOv (true poses, no splits; surface IoU at 3 cm, 2026-12-04): supervoxel 0.898 (no
  // optimisation 0.941), back-projection 0.867 (0.930); by voxel sets (earlier versions) 0.764
  // (0.818) and 0.704 (0.786). The C5 rules themselves: unit tests DeletionRule, MergeRule...
  EXPECT_GE(totals["no optimisation"], truth_total + 10) << "the noise must make duplicates for C5 to remove";
  EXPECT_LT(totals["merge only"], totals["no optimisation"]) << "merging removes duplicates";
  EXPECT_LT(errors["both"], errors["delete only"]) << "merging removes what deletion leaves";
  EXPECT_LE(errors["both"], 3);  // measured 2
  EXPECT_LT(errors["delete only"], errors["no optimisation"]) << "deletion removes the split fragments";
  EXPECT_GT(wov_supervoxel, wov_backprojection);
  EXPECT_GE(wov_supervoxel, 0.86);  // measured 0.898
}
