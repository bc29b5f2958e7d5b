// The projective integrator (nvblox / Open3D style; METHODS B6): every voxel of the blocks
// the truncation bands cross, projected into the depth image.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "tsdf/integrator_common.hpp"
#include "tsdf/ray_traversal.hpp"

namespace semap::integrator_detail {
namespace {

// =============================================================================================
// Projective integration (nvblox / Open3D style)
// =============================================================================================
/// What the voxel loop reads of one pixel, packed: its random reads of depth, colour and label
/// images were three cache misses per voxel (the loop's hottest instructions), now one.
struct PixelSample {
  float depth = 0.0f;  ///< metres, 0 = not usable
  Rgb8 rgb;            ///< from the BGR colour image (zero without one)
  ClassId label = 0;   ///< 0 without a label image
};
static_assert(sizeof(PixelSample) == 8);

/// Row v of the frame as samples (a sequential pass over each input image).
void fill_samples(const IntegrationInput& in, const FrameSetup& f, int v, PixelSample* out) {
  const float* depth = in.depth.ptr<float>(v);
  for (int u = 0; u < f.width; ++u) out[u].depth = usable_depth(depth[u], f.min_range, f.max_range) ? depth[u] : 0.0f;
  if (f.colour) {
    const uint8_t* bgr = in.colour.ptr<uint8_t>(v);
    for (int u = 0; u < f.width; ++u) out[u].rgb = Rgb8{bgr[3 * u + 2], bgr[3 * u + 1], bgr[3 * u]};
  }
  const uint8_t* labels = f.labels ? in.labels.ptr<uint8_t>(v) : nullptr;
  for (int u = 0; u < f.width; ++u) out[u].label = labels ? labels[u] : 0;
}

/// One image row for projective step 1 (block units): its samples, the camera rays' x per
/// column and 1/norm per pixel, the row's ray at x = 0, the ray step per unit x, the camera.
struct BandRow {
  const PixelSample* samples;
  const float* ray_x;
  const float* inv_norm;
  Eigen::Vector3f row_ray, col0, t_blocks;
  float delta;
  int width, stride;
};
using RecentKeys = std::array<uint64_t, 64>;  ///< direct-mapped: keys seen lately

/// Appends the keys of the blocks crossed by the truncation bands of the row's strided usable
/// pixels (first sightings per `recent`); returns those pixels' number. The band ends of 8
/// pixels are computed per step, lane by lane as the per-pixel Eigen expressions (same float
/// operations: same cells), then each pixel's cells are visited.
template <bool kWide>
[[gnu::always_inline]] inline size_t band_blocks(const BandRow& r, RecentKeys& recent, std::vector<uint64_t>& out) {
  constexpr int kLanes = 8;
  auto visit = [&](const Eigen::Vector3i& blk) {
    if (!key_in_range(blk)) return;
    const uint64_t key = pack_key(blk);
    uint64_t& seen = recent[(key * 0x9E3779B97F4A7C15ULL) >> 58];  // any hash: first sightings are kept
    if (seen == key) return;
    seen = key;
    out.push_back(key);
  };
  size_t valid = 0;
  for (int u0 = 0; u0 < r.width; u0 += kLanes * r.stride) {
    std::array<float, kLanes> z, x, inv_norm;
    for (int l = 0; l < kLanes; ++l) {
      const int u = u0 + l * r.stride;
      const int uc = u < r.width ? u : 0;
      z[l] = u < r.width ? r.samples[uc].depth : 0.0f;
      x[l] = r.ray_x[uc];
      inv_norm[l] = r.inv_norm[uc];
    }
    std::array<float, kLanes> a[3], b[3], t_max[3], t_delta[3], s_near, s_far;
    std::array<int, kLanes> ca[3], cb[3], n, step[3];
    for (int l = 0; l < kLanes; ++l) {
      // The pixel's point is z * ray (camera frame), at distance z / inv_norm; the band
      // [dist - delta, dist + delta] along the ray, in block units (no division per pixel).
      const float band = r.delta * inv_norm[l], near = z[l] - band;
      s_near[l] = 0.0f < near ? near : 0.0f;  // std::max(0, near)
      s_far[l] = z[l] + band;
      n[l] = 1;
    }
    for (int i = 0; i < 3; ++i) {  // per axis, 8 lanes per step (branch-free: vectorised)
      const float row_ray = r.row_ray[i], col0 = r.col0[i], t = r.t_blocks[i];
      constexpr float kInf = std::numeric_limits<float>::infinity();
      for (int l = 0; l < kLanes; ++l) {
        const float ray = row_ray + col0 * x[l], pa = t + ray * s_near[l], pb = t + ray * s_far[l];
        a[i][l] = pa;
        b[i][l] = pb;
        const int ta = static_cast<int>(pa), tb = static_cast<int>(pb);  // floor_cells
        const int fa = ta - static_cast<int>(pa < static_cast<float>(ta)), fb = tb - static_cast<int>(pb < static_cast<float>(tb));
        ca[i][l] = fa;
        cb[i][l] = fb;
        n[l] += fb > fa ? fb - fa : fa - fb;
        // traverse_steps' set-up, for every pixel (used where n > 2): the same quotients.
        const float dir = pb - pa;
        const int st = static_cast<int>(dir > 0) - static_cast<int>(dir < 0);
        step[i][l] = st;
        const float q_max = (static_cast<float>(fa + static_cast<int>(st > 0)) - pa) / dir, q_delta = static_cast<float>(st) / dir;
        t_max[i][l] = st == 0 ? kInf : q_max;
        t_delta[i][l] = st == 0 ? kInf : q_delta;
      }
    }
    // The usable pixels split without branches into short segments (n <= 2: as traverse_cells,
    // the end cells are all they cross; visiting c twice when n = 1 emits nothing new) and
    // stepped ones: a branch per pixel on n mispredicted about every other pixel.
    std::array<int8_t, kLanes> short_lanes, long_lanes;
    int n_short = 0, n_long = 0;
    for (int l = 0; l < kLanes; ++l) {
      const bool usable = z[l] != 0.0f;
      short_lanes[n_short] = static_cast<int8_t>(l);
      long_lanes[n_long] = static_cast<int8_t>(l);
      n_short += usable & (n[l] <= 2);
      n_long += usable & (n[l] > 2);
    }
    valid += static_cast<size_t>(n_short + n_long);
    for (int i = 0; i < n_short; ++i) {
      const int l = short_lanes[i];
      visit(Eigen::Vector3i(ca[0][l], ca[1][l], ca[2][l]));
      visit(Eigen::Vector3i(cb[0][l], cb[1][l], cb[2][l]));
    }
    for (int i = 0; i < n_long; ++i) {
      const int l = long_lanes[i];
      step_cells({ca[0][l], ca[1][l], ca[2][l]}, {step[0][l], step[1][l], step[2][l]},
                 {t_max[0][l], t_max[1][l], t_max[2][l]}, {t_delta[0][l], t_delta[1][l], t_delta[2][l]}, n[l], visit);
    }
  }
  return valid;
}
size_t band_blocks_sse2(const BandRow& r, RecentKeys& recent, std::vector<uint64_t>& out) {
  return band_blocks<false>(r, recent, out);
}
SEMAP_TARGET_AVX2 size_t band_blocks_avx2(const BandRow& r, RecentKeys& recent, std::vector<uint64_t>& out) {
  return band_blocks<true>(r, recent, out);
}

/// Frame constants of the voxel projection, as values (voxel stores, bytes that may alias
/// anything, would otherwise make every iteration reload them from the frame set-up).
struct ProjectionFrame {
  float fx, fy, cx, cy, min_range, delta, width, height;
  int width_px;
  const PixelSample* samples;  ///< width x height, then one unusable sample
  int32_t off_image;           ///< index of that unusable sample
};

/// The voxels of one block the frame updates (METHODS B6: a usable pixel, d > -delta): the
/// first `count` entries of voxel (local index), pixel and sdf (along the ray). Pass 1's
/// per-voxel geometry is indexed column-major (y fastest: t = y + 8 (x + 8 z)).
struct BlockHits {
  std::array<int32_t, kBlockVoxels> column_pixel;
  std::array<float, kBlockVoxels> column_z, column_norm, column_inv_z;
  std::array<int32_t, kBlockVoxels> pixel;
  std::array<float, kBlockVoxels> sdf;
  std::array<uint16_t, kBlockVoxels> voxel;
  int count = 0;
};

/// Projects the 512 voxels of a block (camera-frame centre of voxel 0 and the per-axis steps)
/// without branches. Pass 1 finds every voxel's pixel (nearest; the unusable off-image sample
/// when behind the camera or outside) 8 voxels at a time: the 8 rows y of a block column, each
/// lane stepping along x by + step_x as one voxel-row loop would (the same float operations,
/// so the same pixels and distances, now vectorised). Pass 2 reads all their depths with
/// independent loads (the cache misses overlap instead of serialising behind mispredicted
/// branches) and lists the voxels to update.
[[gnu::always_inline]] inline void project_block(const Eigen::Vector3f& base, const Eigen::Vector3f& step_x, const Eigen::Vector3f& step_y,
                          const Eigen::Vector3f& step_z, const ProjectionFrame& f, BlockHits& h) {
  const float sx = step_x.x(), sy = step_x.y(), sz = step_x.z();
  for (int z = 0; z < kBlockSide; ++z) {
    std::array<float, kBlockSide> px, py, pz;  // camera-frame voxel centres of column x, by y
    for (int y = 0; y < kBlockSide; ++y) {
      const Eigen::Vector3f row = base + step_y * static_cast<float>(y) + step_z * static_cast<float>(z);
      px[y] = row.x(), py[y] = row.y(), pz[y] = row.z();
    }
    for (int x = 0; x < kBlockSide; ++x) {
      const int t0 = kBlockSide * (x + kBlockSide * z);
      for (int y = 0; y < kBlockSide; ++y) {
        const float cz = pz[y], inv_z = 1.0f / cz;
        // Nearest pixel: floor(x + 0.5). For x in [0, W) truncation is that floor; the test on
        // the float (false for NaN too) skips the same pixels as floor(x) outside [0, W).
        const float x_pix = f.fx * px[y] * inv_z + f.cx + 0.5f, y_pix = f.fy * py[y] * inv_z + f.cy + 0.5f;
        const bool in_image = (cz > f.min_range) & (x_pix >= 0.0f) & (x_pix < f.width) & (y_pix >= 0.0f) & (y_pix < f.height);
        h.column_pixel[t0 + y] = in_image ? static_cast<int>(y_pix) * f.width_px + static_cast<int>(x_pix) : f.off_image;
        h.column_z[t0 + y] = cz;
        h.column_norm[t0 + y] = std::sqrt(px[y] * px[y] + (py[y] * py[y] + cz * cz));  // Eigen's norm() order
        h.column_inv_z[t0 + y] = inv_z;
        px[y] += sx, py[y] += sy, pz[y] += sz;
      }
    }
  }
  int n = 0;
  for (int t = 0; t < kBlockVoxels; ++t) {
    const int32_t pixel = h.column_pixel[t];
    const float depth = f.samples[pixel].depth;
    const float sdf = (depth - h.column_z[t]) * h.column_norm[t] * h.column_inv_z[t];  // along the ray
    h.pixel[n] = pixel;
    h.sdf[n] = sdf;
    h.voxel[n] = static_cast<uint16_t>(((t >> 3) & 7) | ((t & 7) << 3) | (t & ~63));  // x + 8 y + 64 z
    n += depth != 0.0f && !(sdf <= -f.delta);
  }
  h.count = n;
}

/// What the per-block voxel work of one projective frame reads.
struct BlockPass {
  const VoxelUpdater& updater;
  const ProjectionFrame& frame;
  const FrameSetup& f;
  const IntegrationInput& in;
  const ClassDistribution* label_observations;  ///< by label: labels without confidence (A6)
  const ClassDistribution* pixel_observations;  ///< by pixel: probability images, else null
  float block_size;
  bool bayes, colour;
};

/// Projects a block's voxels and applies B6 (+ labels, colour) to those the frame updates;
/// returns their number. Passes 1-2 branch-free (project_block), pass 3 updates the hits.
template <bool kNativeHalf>
[[gnu::always_inline]] inline size_t integrate_block(Block& block, const BlockPass& p) {
  const FrameSetup& f = p.f;
  const Eigen::Vector3f origin = block.index.cast<float>() * p.block_size + Eigen::Vector3f::Constant(0.5f * f.s);
  const Eigen::Vector3f base = f.R_cw * origin + f.t_cw;
  const Eigen::Vector3f step_x = f.R_cw.col(0) * f.s, step_y = f.R_cw.col(1) * f.s, step_z = f.R_cw.col(2) * f.s;
  BlockHits hits;
  project_block(base, step_x, step_y, step_z, p.frame, hits);
  size_t n = 0;
  ClassDistribution confidence_observation;  // outside the loop: not zeroed per voxel
  for (int j = 0; j < hits.count; ++j) {
    const int li = hits.voxel[j];
    const size_t pix = static_cast<size_t>(hits.pixel[j]);
    const PixelSample& sample = p.frame.samples[pix];  // in cache since pass 2
    const float depth = sample.depth, sdf = hits.sdf[j];
    const ClassId label = sample.label;
    const ClassDistribution* obs = nullptr;
    if (p.bayes && label != 0) {
      if (p.pixel_observations) {
        obs = &p.pixel_observations[pix];
      } else if (f.confidence) {
        const size_t W = static_cast<size_t>(f.width);
        const float c = std::clamp(p.in.confidence.ptr<float>(static_cast<int>(pix / W))[pix % W], 0.01f, 0.999f);
        confidence_observation = ClassDistribution::from_label(label, c, f.confusion_classes);
        obs = &confidence_observation;
      } else {
        obs = &p.label_observations[label];
      }
    }
    n += p.updater.update<kNativeHalf>(block, li, sdf, 1.0f / (depth * depth), label, label != 0 ? f.label_band(depth) : 0.0f,
                                       obs, p.colour ? &sample.rgb : nullptr);
  }
  return n;
}

/// The baseline x86-64 build (SSE2, hand-rolled binary16) and one for CPUs with AVX2 and F16C
/// (16 voxels per pass-1 step, hardware binary16), chosen at run time. No FMA in either: the
/// same roundings, so the same map (checked by bench_tsdf's map_checksum).
size_t integrate_block_sse2(Block& block, const BlockPass& p) { return integrate_block<false>(block, p); }
SEMAP_TARGET_AVX2 size_t integrate_block_avx2(Block& block, const BlockPass& p) {
  return integrate_block<true>(block, p);
}

class ProjectiveIntegrator final : public ArenaIntegrator {
 public:
  explicit ProjectiveIntegrator(const TsdfConfig& cfg) : ArenaIntegrator(cfg) {}
  std::string name() const override { return "projective"; }

 private:
  void run(TsdfMap& map, const IntegrationInput& in, const FrameSetup& f) override {
    const int W = f.width, H = f.height;
    const float block_size = map.block_size();
    // 1. Blocks crossed by each pixel's truncation band (parallel over fixed row chunks).
    const int stride = map.config().allocation_stride;
    const int kRowsPerChunk = 8 * stride;
    const int n_chunks = (H + kRowsPerChunk - 1) / kRowsPerChunk;
    chunk_blocks_.resize(n_chunks);
    samples_.resize(static_cast<size_t>(W) * H + 1);  // + the unusable pixel off-image voxels read
    samples_.back() = PixelSample{};
    rays_.update(f);
    const Eigen::Matrix3f R_blocks = f.R_wc / block_size;  // camera -> world, in block units
    const Eigen::Vector3f t_blocks = f.t_wc / block_size;
    std::vector<size_t> valid(n_chunks, 0);
    const bool avx2 = have_avx2_f16c();
    tbb::parallel_for(0, n_chunks, [&](int c) {
      std::vector<uint64_t>& out = chunk_blocks_[c];
      out.clear();
      // Small direct-mapped cache to skip repeated keys of neighbouring pixels.
      RecentKeys recent;
      recent.fill(~0ULL);
      for (int v = c * kRowsPerChunk; v < std::min(H, (c + 1) * kRowsPerChunk); ++v) {
        // Every row, in one sequential pass: the depth (0 = unusable), colour and label that
        // step 2 looks up at random come from this warm packed copy (PixelSample).
        PixelSample* samples = &samples_[static_cast<size_t>(v) * W];
        fill_samples(in, f, v, samples);
        if (v % stride != 0) continue;
        const BandRow row{samples,
                          rays_.x.data(),
                          &rays_.inv_norm[static_cast<size_t>(v) * W],
                          R_blocks * Eigen::Vector3f(0.0f, rays_.y[v], 1.0f),
                          R_blocks.col(0),
                          t_blocks,
                          f.delta,
                          W,
                          stride};
        valid[c] += avx2 ? band_blocks_avx2(row, recent, out) : band_blocks_sse2(row, recent, out);
      }
    });
    TouchedBlocks touched;
    touched.stamp = map.next_frame_stamp();
    for (int c = 0; c < n_chunks; ++c) {
      stats_.valid_pixels += valid[c];
      for (uint64_t key : chunk_blocks_[c]) {
        const BlockIndex b(static_cast<int>(key & ((1u << kKeyBits) - 1)) - kKeyOffset,
                           static_cast<int>((key >> kKeyBits) & ((1u << kKeyBits) - 1)) - kKeyOffset,
                           static_cast<int>(key >> (2 * kKeyBits)) - kKeyOffset);
        touched.touch(map, b);
      }
    }
    // Per-pixel Bayesian observations (only with probability images).
    const bool bayes = map.has_bayes_layer() && f.labels;
    if (bayes && f.probabilities) {
      pixel_observations_.resize(static_cast<size_t>(W) * H);
      const int k = map.bayes().k();
      tbb::parallel_for(0, H, [&](int v) {
        const float* probs = in.probabilities.ptr<float>(v);
        for (int u = 0; u < W; ++u)
          pixel_observations_[static_cast<size_t>(v) * W + u] =
              ClassDistribution::from_probabilities(probs + static_cast<size_t>(u) * f.prob_channels, f.prob_channels, k);
      });
    }
    // 2. Project every voxel of every touched block (parallel per block).
    const VoxelUpdater updater = make_updater(map, f);
    const bool colour = f.colour && map.has_colour_layer();
    std::vector<size_t> updates(touched.blocks.size(), 0);
    // Label-only observations depend on the label alone: one per class, not one per voxel (A6).
    if (bayes && !f.probabilities && !f.confidence)
      for (int l = 1; l < kNumClasses; ++l)
        label_observations_[l] =
            ClassDistribution::from_label(static_cast<ClassId>(l), f.default_confidence, f.confusion_classes);
    // Frame constants as locals: the voxel stores (bytes, which may alias anything) would
    // otherwise make every iteration reload them.
    const ProjectionFrame frame{f.fx, f.fy, f.cx, f.cy, f.min_range, f.delta, static_cast<float>(W),
                                static_cast<float>(H), W, samples_.data(), static_cast<int32_t>(static_cast<size_t>(W) * H)};
    const BlockPass pass{updater, frame, f, in, label_observations_.data(),
                         bayes && f.probabilities ? pixel_observations_.data() : nullptr, block_size, bayes, colour};
    tbb::parallel_for(size_t{0}, touched.blocks.size(), [&](size_t k) {
      Block& block = *touched.blocks[k];
      const size_t n = avx2 ? integrate_block_avx2(block, pass) : integrate_block_sse2(block, pass);
      if (n) block.mesh_dirty = true;
      updates[k] = n;
    });
    for (size_t n : updates) stats_.voxel_updates += n;
    stats_.touched_blocks = touched.blocks.size();
    stats_.allocated_blocks = touched.allocated;
  }

  /// Camera rays of the depth pixels, kept while the intrinsics and image size stay: pixel (u, v)
  /// at depth z is the camera point z * (x[u], y[v], 1), at distance z / inv_norm[v * W + u].
  struct PixelRays {
    float fx = 0, fy = 0, cx = 0, cy = 0;
    int width = 0, height = 0;
    std::vector<float> x, y, inv_norm;
    void update(const FrameSetup& f) {
      if (f.fx == fx && f.fy == fy && f.cx == cx && f.cy == cy && f.width == width && f.height == height) return;
      fx = f.fx, fy = f.fy, cx = f.cx, cy = f.cy, width = f.width, height = f.height;
      x.resize(width);
      y.resize(height);
      inv_norm.resize(static_cast<size_t>(width) * height);
      for (int u = 0; u < width; ++u) x[u] = (u - cx) / fx;
      for (int v = 0; v < height; ++v) y[v] = (v - cy) / fy;
      for (int v = 0; v < height; ++v)
        for (int u = 0; u < width; ++u)
          inv_norm[static_cast<size_t>(v) * width + u] = 1.0f / std::sqrt(1.0f + x[u] * x[u] + y[v] * y[v]);
    }
  };

  std::vector<std::vector<uint64_t>> chunk_blocks_;
  PixelRays rays_;
  /// The frame per pixel (step 1 -> step 2): depth (0 where not usable), colour, label.
  std::vector<PixelSample> samples_;
  std::vector<ClassDistribution> pixel_observations_;
  std::array<ClassDistribution, kNumClasses> label_observations_;  ///< by label, labels without confidence
};

}  // namespace

std::unique_ptr<Integrator> make_projective_integrator(const TsdfConfig& config) {
  return std::make_unique<ProjectiveIntegrator>(config);
}

}  // namespace semap::integrator_detail
