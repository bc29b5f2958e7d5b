// Temporal label filter (METHODS B1) on the noisy synthetic mode: frames rendered by synth/,
// labels corrupted by synth's apply_segmentation_noise (region flicker + pixel flicker +
// misses + merges + border noise), then filtered by the seed's 5-frame intersection and by
// the depth+pose warped variant. Measured: wrong-label rate (labelled pixels whose label
// differs from ground truth) before/after, and coverage (fraction of ground-truth-labelled
// pixels still carrying the correct label).
#include <gtest/gtest.h>

#include "segmentation/temporal_filter.hpp"
#include "synth/renderer.hpp"
#include "synth/scene.hpp"
#include "semap/synth/segmentation_noise.hpp"
#include "synth/trajectory.hpp"

namespace semap {
namespace {

struct LabelStats {
  long labelled = 0, wrong = 0, correct = 0, gt_labelled = 0;
  void add(const cv::Mat& out, const cv::Mat& gt) {
    for (int v = 0; v < gt.rows; ++v)
      for (int u = 0; u < gt.cols; ++u) {
        const uint8_t g = gt.at<uint8_t>(v, u), o = out.at<uint8_t>(v, u);
        if (!g) continue;
        ++gt_labelled;
        if (!o) continue;
        ++labelled;
        (o == g ? correct : wrong)++;
      }
  }
  double wrong_rate() const { return labelled ? double(wrong) / labelled : 0; }
  double coverage() const { return gt_labelled ? double(correct) / gt_labelled : 0; }
};

struct FilterRun {
  LabelStats before, seed, warped;
};

// Consecutive frames `step` apart on the 300-frame synthetic loop (step 1 = 30 fps motion).
FilterRun run_filters(int step) {
  const SyntheticScene scene = make_scene(3, 12);
  const PinholeIntrinsics k = synth_intrinsics(160, 120);
  SegmentationNoiseParams noise;
  noise.flicker_rate = 0.2;
  noise.pixel_flicker_rate = 0.05;
  TemporalFilterConfig seed_cfg;
  seed_cfg.method = TemporalMethod::seed;
  TemporalFilterConfig warped_cfg = seed_cfg;
  warped_cfg.method = TemporalMethod::warped;
  TemporalLabelFilter seed_filter(seed_cfg, k), warped_filter(warped_cfg, k);
  FilterRun run;
  const int frames = 24, loop = 300;
  for (int i = 0; i < frames; ++i) {
    const Pose T = loop_pose(scene.room.size, i * step, loop);
    const RenderedFrame f = render(scene, T, k);
    const auto [noisy, noisy_instances] = apply_segmentation_noise(f.labels, f.instances, 1000 + i, noise);
    const cv::Mat s = seed_filter.apply(noisy);
    const cv::Mat w = warped_filter.apply(noisy, f.depth, T);
    if (i < seed_cfg.window - 1) continue;  // no history yet: both output nothing
    run.before.add(noisy, f.labels);
    run.seed.add(s, f.labels);
    run.warped.add(w, f.labels);
  }
  std::printf("noisy synthetic (flicker 0.2, pixel flicker 0.05), 20 frames, step %d: wrong-label rate before %.4f "
              "(coverage %.3f) | seed 5-frame %.4f (coverage %.3f) | warped 5-frame %.4f (coverage %.3f)\n",
              step, run.before.wrong_rate(), run.before.coverage(), run.seed.wrong_rate(), run.seed.coverage(),
              run.warped.wrong_rate(), run.warped.coverage());
  return run;
}

TEST(TemporalFilter, BothVariantsReduceWrongLabelsOnNoisySynthetic) {
  for (int step : {1, 4}) {
    const FilterRun r = run_filters(step);
    EXPECT_GT(r.before.wrong_rate(), 0.05);
    EXPECT_LT(r.seed.wrong_rate(), 0.5 * r.before.wrong_rate());
    EXPECT_LT(r.warped.wrong_rate(), 0.5 * r.before.wrong_rate());
    // Under camera motion the warped variant keeps more correct labels than the same-pixel rule.
    EXPECT_GT(r.warped.coverage(), r.seed.coverage());
  }
}

TEST(TemporalFilter, StaticCameraSeedKeepsConsistentLabels) {
  TemporalFilterConfig cfg;
  cfg.method = TemporalMethod::seed;
  TemporalLabelFilter f(cfg, PinholeIntrinsics{});
  cv::Mat labels(10, 10, CV_8UC1, cv::Scalar(5));
  for (int i = 0; i < 4; ++i) EXPECT_EQ(cv::countNonZero(f.apply(labels)), 0);  // no history yet
  EXPECT_EQ(cv::countNonZero(f.apply(labels)), 100);
  cv::Mat changed = labels.clone();
  changed.at<uint8_t>(3, 3) = 7;
  const cv::Mat out = f.apply(changed);
  EXPECT_EQ(out.at<uint8_t>(3, 3), 0);
  EXPECT_EQ(cv::countNonZero(out), 99);
}

}  // namespace
}  // namespace semap
