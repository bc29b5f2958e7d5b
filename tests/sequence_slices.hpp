#pragma once
// Subsampled / reversed / gapped versions of a shared RGB-D sequence, written as a TUM-layout
// folder in a temp dir (issue 16): links to the source images, every k-th line of the lists,
// the ground truth of the kept frames and a dataset.yaml with the camera. Nothing is copied
// into the repo, only generated at test time. Works for any layout open_dataset() reads
// (tum_fr1_rpy, 7scenes_redkitchen: 7-Scenes depth in mm, 65535 invalid, is read by the TUM
// reader with the yaml's depth_scale).
#include <cstddef>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

namespace semap::test {

struct SliceSpec {
  size_t first = 0;                                   ///< first source frame (reader index)
  size_t last = std::numeric_limits<size_t>::max();  ///< last source frame, inclusive (clamped)
  size_t step = 1;                                    ///< every step-th frame (k)
  bool reverse = false;                               ///< play the kept frames backwards
  /// Output frames [blank_begin, blank_end) are replaced by all-zero depth and black RGB (a
  /// dropped / covered sensor); the ground truth keeps their true poses.
  size_t blank_begin = 0, blank_end = 0;
  /// Explicit source frames (increasing reader indices), e.g. frames_by_motion(): used instead
  /// of first / last / step when not empty.
  std::vector<size_t> frames;
};

struct SequenceSlice {
  std::filesystem::path dir;        ///< the TUM-layout folder (open with open_dataset)
  std::vector<size_t> source_index;  ///< output frame i -> source reader index
  std::vector<bool> blank;           ///< output frame i was blanked
  size_t size() const { return source_index.size(); }
};

/// Writes the slice of `source_dir` described by `spec` into `out_dir` (created; must be
/// empty or absent). Timestamps stay those of the source (reversed slices get mirrored,
/// increasing timestamps, the ground truth follows them). Throws semap::Error naming the
/// source when it has no ground truth or the slice is empty.
SequenceSlice write_sequence_slice(const std::filesystem::path& source_dir, const SliceSpec& spec,
                                   const std::filesystem::path& out_dir);

/// Keyframe-rate frames (issue 42): the first frame, then each frame whose ground-truth pose is
/// at least `min_translation_m` or `min_rotation_deg` from the last one kept, as a robot that
/// records at 1-2 Hz would give. The ground truth only chooses the frames. Throws semap::Error
/// naming the source when a frame has no ground truth.
std::vector<size_t> frames_by_motion(const std::filesystem::path& source_dir, double min_translation_m,
                                     double min_rotation_deg);

/// "k=5 frames 0..499" style label for logs.
std::string describe(const SliceSpec& spec);

}  // namespace semap::test
