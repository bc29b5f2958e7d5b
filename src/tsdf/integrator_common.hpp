#pragma once
// Internal to the integrators (integrator.cpp, grouped_integrator.cpp, projective_integrator.cpp):
// the per-frame set-up, the voxel update rules (METHODS B6 + label and colour layers), the
// run-time ISA dispatch, touched-block bookkeeping and the ArenaIntegrator base. Not installed.
#include <tbb/task_arena.h>

#if defined(__x86_64__) || defined(__i386__)
#include <emmintrin.h>
#define SEMAP_TSDF_X86 1
// The integrators' per-block work is also built for AVX2 + F16C, chosen at run time.
#define SEMAP_TARGET_AVX2 [[gnu::target("avx2,f16c")]]
#else
#define SEMAP_TARGET_AVX2
#endif

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/cpu_time.hpp"
#include "tsdf/integrator.hpp"

namespace semap::integrator_detail {

/// False for NaN. Both comparisons, no short-circuit: a branch-free lane in vectorised loops.
inline bool usable_depth(float z, float min_range, float max_range) { return (z > min_range) & (z <= max_range); }

/// Per-frame constants shared by both integrators.
struct FrameSetup {
  int width = 0, height = 0;
  float fx, fy, cx, cy;
  Eigen::Matrix3f R_wc;  // world <- camera
  Eigen::Vector3f t_wc;  // camera centre in the world
  Eigen::Matrix3f R_cw;
  Eigen::Vector3f t_cw;
  float s, delta, eps, min_range, max_range, default_confidence;
  float label_band_min, label_band_sigmas;
  DepthNoiseModel depth_noise;
  int confusion_classes = kNumRealClasses - 1;
  bool labels = false, confidence = false, probabilities = false, colour = false;
  int prob_channels = 0;

  /// Labels update the voxels within this of depth z's surface (|d| <= band): label_band_voxels
  /// voxels, widened to label_band_sigmas depth-noise sigmas, at most the truncation.
  float label_band(float z) const {
    return std::min(delta, std::max(label_band_min, label_band_sigmas * static_cast<float>(depth_noise.sigma_m(z))));
  }
};

FrameSetup setup_frame(const TsdfMap& map, const IntegrationInput& in);

/// Context of the per-voxel update of METHODS B6 (+ label and colour layers).
struct VoxelUpdater {
  const WeightQuantizer& wq;
  const BayesLayerCodec& bayes;
  float delta, eps, w_max;
  bool label_layer, bayes_layer, colour_layer;

  /// d: signed distance (positive in front), w: ray weight before the drop-off; labels update
  /// within label_band (FrameSetup::label_band). Returns false when nothing was updated (beyond -delta).
  /// Inlined into the voxel loops (measured: a call per update cost ~5 % of a projective frame).
  /// kNativeHalf: binary16 by the compiler's _Float16 (F16C instructions in a function built
  /// for them), the same IEEE round-to-nearest-even values as the hand-rolled conversions.
  template <bool kNativeHalf = false>
  [[gnu::always_inline]] bool update(Block& block, int li, float d, float w, ClassId label, float label_band,
                                     const ClassDistribution* observation, const Rgb8* colour) const {
    if (d <= -delta) return false;
    if (d < -eps) w *= (delta + d) / (delta - eps);  // B6 linear drop-off behind the surface
    if (d > delta) d = delta;
    TsdfVoxel& v = block.voxels[li];
    const float W = wq.decode(v.weight_q);
    const float W_new = W + w;
    const float D = kNativeHalf ? native_half_to_float(v.sdf_half) : v.sdf();
    const float D_new = W > 0 ? (W * D + w * d) / W_new : d;
    v.sdf_half = kNativeHalf ? native_float_to_half(D_new) : float_to_half(D_new);
    v.weight_q = wq.encode_from(std::min(W_new, w_max), v.weight_q);
    if (colour_layer && colour) {
      Rgb8& c = block.colour[li];
      const float a = W / W_new, b = w / W_new;
      // + 0.5 and truncation: rounding of a non-negative value, without a libm call per voxel.
      c.r = static_cast<uint8_t>(a * c.r + b * colour->r + 0.5f);
      c.g = static_cast<uint8_t>(a * c.g + b * colour->g + 0.5f);
      c.b = static_cast<uint8_t>(a * c.b + b * colour->b + 0.5f);
    }
    if (label != 0 && std::fabs(d) <= label_band) update_labels(block, li, label, observation);
    return true;
  }
  /// Label layers: call once per voxel per frame (one frame, one observation).
  void update_labels(Block& block, int li, ClassId label, const ClassDistribution* observation) const {
    if (label_layer) compact_label_vote(block.voxels[li].label, block.label_confidence[li], label);
    if (bayes_layer && observation) bayes.update(&block.bayes[static_cast<size_t>(li) * bayes.bytes_per_voxel()], *observation);
  }
};

VoxelUpdater make_updater(const TsdfMap& map, const FrameSetup& f);

/// Whether this CPU runs the integrators' AVX2 + F16C builds (checked once). The environment
/// variable SEMAP_TSDF_BASELINE_ISA forces the baseline builds (to check both give one map).
bool have_avx2_f16c();

/// Touched-block bookkeeping of one frame: blocks get a dense index via their frame stamp.
struct TouchedBlocks {
  std::vector<Block*> blocks;
  uint32_t stamp = 0;
  size_t allocated = 0;
  /// `found`: the block when the caller already looked it up (nullptr: looked up here).
  int32_t touch(TsdfMap& map, const BlockIndex& b, Block* found = nullptr) {
    Block* block = found ? found : map.find_block(b);
    if (!block) {
      block = &map.allocate_block(b);
      ++allocated;
    }
    if (block->frame_stamp != stamp) {
      block->frame_stamp = stamp;
      block->frame_slot = static_cast<int32_t>(blocks.size());
      blocks.push_back(block);
    }
    return block->frame_slot;
  }
};

// Both integrators: frame set-up, the run inside the configured TBB arena, and the
// optional drop of far blocks (issue 8 memory bound) are the same; only run() differs.
class ArenaIntegrator : public Integrator {
 public:
  explicit ArenaIntegrator(const TsdfConfig& cfg);
  double worker_cpu_ms() const override { return worker_cpu_.total_ms(); }
  void integrate(TsdfMap& map, const IntegrationInput& in) override;

 protected:
  virtual void run(TsdfMap& map, const IntegrationInput& in, const FrameSetup& f) = 0;

 private:
  tbb::task_arena arena_;
  ArenaWorkerCpu worker_cpu_;
};

/// The integrators, each defined in its own file (make_integrator picks one).
std::unique_ptr<Integrator> make_grouped_integrator(const TsdfConfig& config);
std::unique_ptr<Integrator> make_projective_integrator(const TsdfConfig& config);

}  // namespace semap::integrator_detail
