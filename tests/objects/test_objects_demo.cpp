// The object map of `semap demo` (issue 17): the synthetic loop of the demo (240 frames, seed 1,
// depth noise), tracked poses and the built-in noisy segmenter (20 % flicker, missed and merged
// masks), run end to end. The object map must hold up about as well as the TSDF labels do:
// weighted overlap (METHODS C6) >= 0.75 and the object count within one of the ground truth.
// Heavy: it renders and maps the whole demo (about 100 s on 2 cores).
// Status (issue 17): the count holds (11 for 12) but WOv is 0.48: the objects' points are a
// noisy shell under depth noise (ground-truth masks on the same data give 0.52), see README.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>

#include "semap/pipeline/run_pipeline.hpp"
#include "synth/synth_config.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

TEST(ObjectsDemo, TrackedNoisyDemoKeepsTheObjects) {
  test::TempDir dir("objects_demo");
  SynthConfig synth;  // as cmd_demo: 240 frames, seed 1, depth noise
  synth.frames = 240;
  synth.seed = 1;
  synth.depth_noise = true;
  generate_dataset(synth, dir / "dataset");
  RunOptions options;
  options.dataset = dir / "dataset";
  options.out_dir = dir / "out";
  options.poses = PoseSource::track;
  options.segmenter = "groundtruth";
  options.seg_noise = 0.2;
  options.show_progress = false;
  const RunResult result = run_pipeline(options, SemapConfig{});
  ASSERT_TRUE(result.evaluation.objects.has_value()) << result.evaluation.note;
  const ObjectEvaluation& objects = *result.evaluation.objects;
  std::printf("demo objects: WOv %.3f (same class %.3f), %zu objects for %zu in the ground truth\n", objects.wov,
              objects.wov_same_class, objects.map_objects, objects.gt_objects);
  for (const ObjectClassCount& c : objects.counts)
    std::printf("  %-10s map %zu  gt %zu\n", std::string(class_name(c.class_id)).c_str(), c.map, c.gt);
  EXPECT_GE(objects.wov, 0.75);
  EXPECT_LE(std::abs(static_cast<long>(objects.map_objects) - static_cast<long>(objects.gt_objects)), 1L);
}

}  // namespace
}  // namespace semap
