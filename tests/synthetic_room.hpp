#pragma once
// The small synthetic room that several suites map (pipeline, navigation): 90 frames of seed 3
// with 10 objects at 320x240, made once per build of the calling test binary and copied per
// test process (shared_fixture.hpp).
#include <filesystem>

#include "semap/io/dataset.hpp"
#include "semap/mapper.hpp"
#include "shared_fixture.hpp"
#include "synth/synth_config.hpp"

namespace semap::test {

/// Copies the room's dataset into `dest` (which must not exist).
inline void copy_small_synthetic_room(const std::filesystem::path& dest) {
  copy_shared_fixture("pipeline_90_frames_seed_3", "/proc/self/exe", [](const std::filesystem::path& to) {
    SynthConfig synth;
    synth.frames = 90;
    synth.seed = 3;
    synth.objects = 10;
    synth.width = 320;
    synth.height = 240;
    generate_dataset(synth, to);
  }, dest);
}

/// Maps the first `frames` frames of a synthetic recording the way a library user with their
/// own poses and segmentation does (FrameHints: ground-truth pose and masks), then finishes.
inline void map_with_ground_truth_hints(Mapper& mapper, const DatasetReader& dataset, size_t frames) {
  for (size_t i = 0; i < frames; ++i) {
    const Frame frame = dataset.load(i);
    FrameHints hints;
    hints.T_world_camera = frame.gt_T_world_camera;
    hints.segmentation = segmentation_from_label_images(frame.labels, frame.instances);
    mapper.add_frame(frame, hints);
  }
  mapper.finish();
}

}  // namespace semap::test
