// The WHOLE map.semap as `semap run --resume` and `semap merge` read it (issue 44): Mapper::load
// reads the container (core/archive.cpp), the config and camera sections (pipeline/map_archive),
// the TSDF (tsdf/map_io), the object map (objects/object_map_io) and the keyframes with their
// fern codes and pose graph (tracking/tracker_state), and restores each stage from them.
// fuzz_map covers the container and the TSDF section only.
// The input is the file without its trailing checksum: as fuzz_map, the target appends the
// FNV-1a 64 of bytes [12, end) so that the fuzzer reaches the sections; every 64th input is
// loaded as-is (checksum/truncation paths).
// Seeds (only when SEMAP_FUZZ_SEED_DIR is set; ~20 s under ASan): the first 5 frames of a
// synthetic room (112x84, 12 objects) mapped by Mapper with the ground-truth segmenter and saved
// by Mapper::save, once tracked (its first 2 keyframes kept, images at half size: 56 KB, 2
// objects and their best views) and once with given poses (no tracking section: 20 KB, 2 objects).
#include <cstdio>
#include <cstring>

#include <opencv2/imgproc.hpp>

#include "core/archive.hpp"
#include "core/progress.hpp"
#include "fuzz/fuzz_util.hpp"
#include "segmentation/groundtruth_segmenter.hpp"
#include "semap/core/error.hpp"
#include "semap/io/dataset.hpp"
#include "semap/mapper.hpp"
#include "synth/synth_config.hpp"
#include "tracking/tracker_state.hpp"

namespace {

constexpr size_t kSeedFrames = 5;     // the start of the room's loop: small steps, tracked
constexpr size_t kSeedKeyframes = 2;

/// Maps the room (tracked, or with its ground-truth poses) and writes the saved file as a seed.
void write_map_seed(const std::filesystem::path& room, bool given_poses, const std::string& name) {
  const auto reader = semap::open_dataset(room);
  semap::SemapConfig config;
  config.pipeline.threads = 1;
  config.tsdf.threads = 1;
  config.tsdf.voxel_size = 0.25;  // few blocks: the seed stays under -max_len
  config.tracking.keyframe_translation = 0.02;  // a keyframe every few frames
  config.tracking.keyframe_rotation_deg = 2.0;
  config.objects.map_voxel_size = 0.1;  // few object points
  semap::Mapper mapper(config, reader->camera(), std::make_unique<semap::GroundTruthSegmenter>());
  for (size_t i = 0; i < kSeedFrames; ++i) {
    semap::Frame frame = reader->load(i);
    semap::FrameHints hints;
    if (given_poses) hints.T_world_camera = frame.gt_T_world_camera;
    mapper.add_frame(frame, hints);
  }
  mapper.finish();
  const auto path = semap::fuzz::scratch_dir() / "seed.semap";
  mapper.save(path);
  // The first kSeedKeyframes keyframes and the edges between them: the seed stays small.
  semap::ArchiveSections sections = semap::read_map_archive(path);
  if (sections.count(semap::kTrackingSection)) {
    semap::TrackerState state = semap::decode_tracker_state(sections[semap::kTrackingSection], path);
    const size_t keep = std::min(state.keyframes.size(), kSeedKeyframes);
    state.keyframes.resize(keep);
    for (auto& keyframe : state.keyframes) {  // half-size images (a resume may refuse them: a path too)
      auto small = std::make_shared<semap::Keyframe>(*keyframe);
      cv::resize(keyframe->depth, small->depth, {}, 0.5, 0.5, cv::INTER_NEAREST);
      cv::resize(keyframe->gray, small->gray, {}, 0.5, 0.5, cv::INTER_NEAREST);
      keyframe = small;
    }
    state.T_world_keyframe.resize(keep);
    std::erase_if(state.edges, [&](const auto& e) { return size_t(e.from) >= keep || size_t(e.to) >= keep; });
    sections[semap::kTrackingSection] = semap::encode_tracker_state(state);
    semap::write_map_archive(path, sections);
  }
  const std::string bytes = semap::fuzz::read_bytes(path);
  std::fprintf(stderr, "fuzz_map_archive: seed %s: %zu bytes (%zu keyframes mapped, at most 2 kept), %zu objects, %zu lost frames\n",
               name.c_str(), bytes.size(), mapper.stats().keyframes, mapper.stats().objects, mapper.stats().lost_frames);
  // scripts/ci-fuzz.sh runs with -max_len=65536: a longer seed would be cut before its last
  // sections (the object views were added after this target: the images are 112x84 for that).
  constexpr size_t kMaxLen = 65536;
  if (bytes.size() - 8 > kMaxLen) {
    std::fprintf(stderr, "fuzz_map_archive: seed %s is %zu bytes, over -max_len %zu: make it smaller\n",
                 name.c_str(), bytes.size() - 8, kMaxLen);
    std::abort();
  }
  semap::fuzz::write_seed(name, bytes.substr(0, bytes.size() - 8));
}

}  // namespace

// Mapping the seeds runs PCL's supervoxels, whose point clouds ASan reports as an
// alloc-dealloc mismatch (PCL 1.13 is built as C++14: scripts/ci-sanitize.sh says why); the
// flag is one the fuzz script does not set, so this default stands.
extern "C" const char* __asan_default_options() { return "alloc_dealloc_mismatch=0"; }

// TBB keeps the observer of a thread-local CPU-time helper (core/cpu_time.cpp) past exit.
extern "C" const char* __lsan_default_suppressions() { return "leak:tbb::detail::r1::observe\n"; }

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  semap::Progress::set_mode(-1);
  const char* seed_dir = std::getenv("SEMAP_FUZZ_SEED_DIR");
  if (!seed_dir || !*seed_dir) return 0;  // replaying inputs: no seeds needed
  semap::SynthConfig synth;
  synth.frames = 100;  // rendered in full, the first kSeedFrames mapped
  synth.width = 112;
  synth.height = 84;
  synth.gt_point_spacing = 0.2;  // gt_points.ply is not used here
  synth.seed = 2;
  const auto room = semap::fuzz::scratch_dir() / "room";
  semap::generate_dataset(synth, room);
  write_map_seed(room, false, "tracked.semap");
  write_map_seed(room, true, "given_poses.semap");
  std::filesystem::remove_all(room);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = semap::fuzz::map_input_file(data, size);
  try {
    const auto mapper = semap::Mapper::load(path);
    (void)mapper->stats();
  } catch (const semap::Error&) {
  }
  return 0;
}
