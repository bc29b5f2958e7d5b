// Noisy-segmentation mode (issue 6 "Measured"), like the seed's Tables 1 and 2: objects per
// class for {no optimisation, merge only, delete only, both} and WOv for {mask back-projection,
// supervoxel-guided}. Heavy: it renders a 200-frame sequence and segments 100 keyframes twice.
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

std::vector<KeyframeSegments> segment_sequence(const std::filesystem::path& dataset, const ObjectsConfig& config,
                                               const SegmentationNoiseParams& noise, int frame_step) {
  const auto reader = open_dataset(dataset);
  FrameSegmenter segmenter(config, reader->camera());
  std::vector<KeyframeSegments> out;
  for (size_t i = 0; i < reader->size(); i += frame_step) {
    const Frame frame = reader->load(i);
    const auto [labels, instances] = apply_segmentation_noise(frame.labels, frame.instances, i, noise);
    out.push_back({i, segmenter.segment(frame, test::segmentation_from_labels(labels, instances, 100), *frame.gt_T_world_camera)});
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
    const auto instances = map_sequence(supervoxel_frames, c);
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

  // Optimisation must never make the counts worse; a strict decrease is not asserted. On this
  // scene (since the synthetic world gained touching same-class pairs and the -25 deg camera
  // pitch) the no-optimisation map holds about one instance per visible object: the errors are
  // the noise's merges (the two touching chairs, the bottle on the table) and one flicker false
  // positive (a lamp beside the chairs) that C5 rightly keeps STABLE, since s_i counts every
  // candidacy inside d_assoc (C4) and the chair segments pass it every frame. Measured (160
  // frames, step 2): no-opt / merge / delete / both = 9 objects each, count error 3 (nothing to
  // remove); ground truth 10. WOv supervoxel 0.777 (no opt 0.777; 0.747 before
  // objects.point_mask_refinement), back-projection 0.700 (no opt 0.713). With objects.mask_depth_gate_k = 3: 10 / 9 / 10 / 9, error 4 / 3 / 4 / 3 (a split box
  // is merged back), WOv 0.757 (0.755) and 0.728. The C5 rules themselves: unit tests
  // DeletionRule, MergeRule...
  EXPECT_LE(errors["both"], errors["no optimisation"]);
  EXPECT_LE(totals["both"], totals["no optimisation"]);
  EXPECT_GT(wov_supervoxel, wov_backprojection);
  EXPECT_GE(wov_supervoxel, 0.76);  // measured 0.777
}
