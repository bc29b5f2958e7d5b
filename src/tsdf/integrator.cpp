#include "tsdf/integrator.hpp"

#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#if defined(__x86_64__) || defined(__i386__)
#include <cpuid.h>
#include <emmintrin.h>
#define SEMAP_TSDF_X86 1
// The integrators' per-block work is also built for AVX2 + F16C, chosen at run time.
#define SEMAP_TARGET_AVX2 [[gnu::target("avx2,f16c")]]
#else
#define SEMAP_TARGET_AVX2
#endif

#include <array>
#include <cmath>
#include <cstdlib>
#include <span>
#include <utility>

#include "core/cpu_time.hpp"
#include "semap/core/error.hpp"

namespace semap {
namespace {

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
  float s, delta, eps, label_band, min_range, max_range, default_confidence;
  int confusion_classes = kNumRealClasses - 1;
  bool labels = false, confidence = false, probabilities = false, colour = false;
  int prob_channels = 0;
};

FrameSetup setup_frame(const TsdfMap& map, const IntegrationInput& in) {
  const TsdfConfig& cfg = map.config();
  if (in.depth.empty() || in.depth.type() != CV_32FC1) throw Error("integrate", "depth must be a non-empty CV_32FC1 image");
  auto check = [&](const cv::Mat& m, int type, const char* what) {
    if (m.empty()) return false;
    if (m.rows != in.depth.rows || m.cols != in.depth.cols)
      throw Error("integrate", std::string(what) + " size differs from depth");
    if (type >= 0 && m.type() != type) throw Error("integrate", std::string(what) + " has the wrong pixel type");
    return true;
  };
  FrameSetup f;
  f.width = in.depth.cols;
  f.height = in.depth.rows;
  f.fx = static_cast<float>(in.intrinsics.fx);
  f.fy = static_cast<float>(in.intrinsics.fy);
  f.cx = static_cast<float>(in.intrinsics.cx);
  f.cy = static_cast<float>(in.intrinsics.cy);
  if (!(f.fx > 0 && f.fy > 0)) throw Error("integrate", "intrinsics need fx, fy > 0");
  f.R_wc = in.T_world_camera.linear().cast<float>();
  f.t_wc = in.T_world_camera.translation().cast<float>();
  if (!f.R_wc.allFinite() || !f.t_wc.allFinite()) throw Error("integrate", "pose is not finite");
  f.R_cw = f.R_wc.transpose();
  f.t_cw = -(f.R_cw * f.t_wc);
  f.s = map.voxel_size();
  f.delta = static_cast<float>(cfg.truncation());
  f.eps = static_cast<float>(cfg.epsilon());
  f.label_band = static_cast<float>(cfg.label_band_voxels * cfg.voxel_size);
  f.min_range = static_cast<float>(cfg.min_depth);
  f.max_range = static_cast<float>(cfg.max_depth);
  f.default_confidence = static_cast<float>(cfg.bayes_default_confidence);
  f.confusion_classes = cfg.bayes_confusion_classes;
  f.labels = check(in.labels, CV_8UC1, "labels");
  f.confidence = check(in.confidence, CV_32FC1, "confidence");
  f.colour = check(in.colour, CV_8UC3, "colour");
  if (check(in.probabilities, -1, "probabilities")) {
    if (in.probabilities.depth() != CV_32F) throw Error("integrate", "probabilities must be CV_32FC(n)");
    f.probabilities = true;
    f.prob_channels = in.probabilities.channels();
  }
  return f;
}

/// Context of the per-voxel update of METHODS B6 (+ label and colour layers).
struct VoxelUpdater {
  const WeightQuantizer& wq;
  const BayesLayerCodec& bayes;
  float delta, eps, label_band, w_max;
  bool label_layer, bayes_layer, colour_layer;

  /// d: signed distance (positive in front), w: ray weight before the drop-off.
  /// Returns false when nothing was updated (beyond -delta).
  /// Inlined into the voxel loops (measured: a call per update cost ~5 % of a projective frame).
  /// kNativeHalf: binary16 by the compiler's _Float16 (F16C instructions in a function built
  /// for them), the same IEEE round-to-nearest-even values as the hand-rolled conversions.
  template <bool kNativeHalf = false>
  [[gnu::always_inline]] bool update(Block& block, int li, float d, float w, ClassId label,
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

VoxelUpdater make_updater(const TsdfMap& map, const FrameSetup& f) {
  return VoxelUpdater{map.weights(),        map.bayes(),           f.delta,
                      f.eps,                f.label_band,          static_cast<float>(map.config().weight_max),
                      map.has_label_layer(), map.has_bayes_layer(), map.has_colour_layer()};
}

/// Whether this CPU runs the integrators' AVX2 + F16C builds (checked once). The environment
/// variable SEMAP_TSDF_BASELINE_ISA forces the baseline builds (to check both give one map).
bool have_avx2_f16c() {
#ifdef SEMAP_TSDF_X86
  // F16C through cpuid: clang 14's __builtin_cpu_supports does not know "f16c".
  static const bool yes = [] {
    unsigned eax = 0, ebx = 0, ecx = 0, edx = 0;
    const bool f16c = __get_cpuid(1, &eax, &ebx, &ecx, &edx) && (ecx & bit_F16C);
    return !std::getenv("SEMAP_TSDF_BASELINE_ISA") && __builtin_cpu_supports("avx2") && f16c;
  }();
  return yes;
#else
  return false;
#endif
}

int arena_threads(const TsdfConfig& cfg) { return cfg.threads > 0 ? cfg.threads : tbb::info::default_concurrency(); }

/// floor(x) as a cell index: the truncating cast, one lower for negative non-integers. Equal
/// to std::floor within the int range, without its libm/SSE4.1-less slow path.
inline int32_t floor_cell(float x) {
  const int32_t t = static_cast<int32_t>(x);
  return t - (x < static_cast<float>(t) ? 1 : 0);
}
inline Eigen::Vector3i floor_cells(const Eigen::Vector3f& p) { return {floor_cell(p.x()), floor_cell(p.y()), floor_cell(p.z())}; }

/// Visits n cells from `cell`, each step along the axis of the smallest t_max (ties: as
/// x < y ? (x < z ? x : z) : (y < z ? y : z), i.e. x when x < y and x < z, else y when y < z,
/// else z). The axis is chosen by selects on values kept in registers: a data-dependent branch
/// mispredicts, and an indexed array update went through memory (store-forwarding latency on
/// every step of the loop-carried chain).
template <class Visit>
inline void step_cells(std::array<int, 3> cell, const std::array<int, 3>& step, std::array<float, 3> t_max,
                       const std::array<float, 3>& t_delta, int n, Visit&& visit) {
  int cx = cell[0], cy = cell[1], cz = cell[2];
  float tx = t_max[0], ty = t_max[1], tz = t_max[2];
  for (int i = 0; i < n; ++i) {
    visit(Eigen::Vector3i(cx, cy, cz));
    const bool sx = (tx < ty) & (tx < tz);
    const bool sy = !sx & (ty < tz);
    const bool sz = !sx & !sy;
    cx += sx ? step[0] : 0;
    cy += sy ? step[1] : 0;
    cz += sz ? step[2] : 0;
    tx = sx ? tx + t_delta[0] : tx;
    ty = sy ? ty + t_delta[1] : ty;
    tz = sz ? tz + t_delta[2] : tz;
  }
}

/// The stepping part of traverse_cells: the n cells from c = floor(pa) along pa -> pb.
template <class Visit>
void traverse_steps(const Eigen::Vector3f& pa, const Eigen::Vector3f& pb, const Eigen::Vector3i& c, int n, Visit&& visit) {
  const Eigen::Vector3f dir = pb - pa;
  std::array<int, 3> cell{c.x(), c.y(), c.z()}, step;
  alignas(16) std::array<float, 4> t_max, t_delta, num{0, 0, 0, 0}, den{1, 1, 1, 1}, sign{0, 0, 0, 0};
  for (int i = 0; i < 3; ++i) {
    step[i] = dir[i] > 0 ? 1 : (dir[i] < 0 ? -1 : 0);
    num[i] = static_cast<float>(c[i] + (step[i] > 0 ? 1 : 0)) - pa[i];  // to the first boundary
    den[i] = dir[i];
    sign[i] = static_cast<float>(step[i]);
  }
  // The six divisions as two 4-lane ones (the same IEEE quotients); axes without motion never step.
#ifdef SEMAP_TSDF_X86
  const __m128 d = _mm_load_ps(den.data());
  _mm_store_ps(t_max.data(), _mm_div_ps(_mm_load_ps(num.data()), d));
  _mm_store_ps(t_delta.data(), _mm_div_ps(_mm_load_ps(sign.data()), d));
#else
  for (int i = 0; i < 4; ++i) t_max[i] = num[i] / den[i], t_delta[i] = sign[i] / den[i];
#endif
  for (int i = 0; i < 3; ++i)
    if (step[i] == 0) t_max[i] = t_delta[i] = std::numeric_limits<float>::infinity();
  step_cells(cell, step, {t_max[0], t_max[1], t_max[2]}, {t_delta[0], t_delta[1], t_delta[2]}, n, visit);
}

/// Amanatides-Woo traversal of the unit cells crossed by segment pa -> pb (in cell units).
template <class Visit>
void traverse_cells(const Eigen::Vector3f& pa, const Eigen::Vector3f& pb, Visit&& visit) {
  Eigen::Vector3i c = floor_cells(pa);
  const Eigen::Vector3i end = floor_cells(pb);
  const int n = 1 + std::abs(end.x() - c.x()) + std::abs(end.y() - c.y()) + std::abs(end.z() - c.z());
  if (n <= 2) {  // the common short segment: its end cells are all it crosses, no stepping needed
    visit(c);
    if (n == 2) visit(end);
    return;
  }
  traverse_steps(pa, pb, c, n, visit);
}

// Group keys: 21 bits per axis (voxel indices within +-2^20).
constexpr int kKeyBits = 21;
constexpr int32_t kKeyOffset = 1 << (kKeyBits - 1);
/// Non-zero when a voxel index is outside the key range: each offset coordinate within
/// [0, 2^kKeyBits), as unsigned, one test for all three (an int, for vectorised loops).
inline uint32_t key_range_excess(int32_t x, int32_t y, int32_t z) {
  return (static_cast<uint32_t>(x + kKeyOffset) | static_cast<uint32_t>(y + kKeyOffset) | static_cast<uint32_t>(z + kKeyOffset)) >>
         kKeyBits;
}
inline bool key_in_range(const Eigen::Vector3i& v) { return key_range_excess(v.x(), v.y(), v.z()) == 0; }
inline uint64_t pack_key(const Eigen::Vector3i& v) {
  return static_cast<uint64_t>(v.x() + kKeyOffset) | (static_cast<uint64_t>(v.y() + kKeyOffset) << kKeyBits) |
         (static_cast<uint64_t>(v.z() + kKeyOffset) << (2 * kKeyBits));
}
inline size_t mix_key(uint64_t k) {
  k ^= k >> 33;
  k *= 0xff51afd7ed558ccdULL;
  k ^= k >> 33;
  return static_cast<size_t>(k);
}

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
  explicit ArenaIntegrator(const TsdfConfig& cfg) : arena_(arena_threads(cfg)), worker_cpu_(arena_) {}
  double worker_cpu_ms() const override { return worker_cpu_.total_ms(); }

  void integrate(TsdfMap& map, const IntegrationInput& in) override {
    const FrameSetup f = setup_frame(map, in);
    stats_ = {};
    arena_.execute([&] { run(map, in, f); });
    if (map.config().drop_distance > 0) map.remove_blocks_beyond(f.t_wc, static_cast<float>(map.config().drop_distance));
  }

 protected:
  virtual void run(TsdfMap& map, const IntegrationInput& in, const FrameSetup& f) = 0;

 private:
  tbb::task_arena arena_;
  ArenaWorkerCpu worker_cpu_;
};

/// The voxels one grouped ray crosses (structure of arrays) and their B6 signed distances
/// d(v, p, o) = |p - o| - |v - o|, computed for all of them in one vectorised loop (the same
/// float operations as the Eigen expression per voxel: (v + 0.5) s - o, then its norm).
struct RayCells {
  std::vector<int> x, y, z;
  std::vector<float> d;
  void clear() { x.clear(), y.clear(), z.clear(); }
  void add(const Eigen::Vector3i& v) { x.push_back(v.x()), y.push_back(v.y()), z.push_back(v.z()); }
  size_t size() const { return x.size(); }
  Eigen::Vector3i voxel(size_t j) const { return {x[j], y[j], z[j]}; }
  void distances(float dist, float s, const Eigen::Vector3f& o) {
    d.resize(x.size());
    const int* cx = x.data(); const int* cy = y.data(); const int* cz = z.data();
    float* out = d.data();
    const float ox = o.x(), oy = o.y(), oz = o.z();
    for (size_t j = 0; j < x.size(); ++j) {
      const float px = (static_cast<float>(cx[j]) + 0.5f) * s - ox, py = (static_cast<float>(cy[j]) + 0.5f) * s - oy,
                  pz = (static_cast<float>(cz[j]) + 0.5f) * s - oz;
      out[j] = dist - std::sqrt(px * px + (py * py + pz * pz));  // Eigen's norm() order
    }
  }
};

/// One image row's pixels in the world (structure of arrays) with their voxels and B6
/// weights 1/z^2; w = 0 where a pixel has no group (unusable depth, voxel out of key range).
struct RowPoints {
  std::vector<float> x, y, z, w;
  std::vector<int32_t> vx, vy, vz;
  uint64_t key(int u) const { return pack_key(Eigen::Vector3i(vx[u], vy[u], vz[u])); }
};

/// What back-projecting one row needs: the world ray of pixel u is d(u) = col0 * (u - cx) / fx
/// + ray0, its point t + z d(u).
struct RowRays {
  float r00, r10, r20;  ///< col0 = R_wc's first column
  float q0, q1, q2;     ///< ray0 = R_wc (0, (v - cy) / fy, 1)
  float tx, ty, tz, cx, inv_fx, inv_s, min_range, max_range;
};

/// The lanes of back_project_row, as restrict parameters (GCC ignores restrict on locals; its
/// 25 alias checks between the seven outputs kept the loop scalar). Ints, not bools, and no
/// short-circuit: the loop vectorises (checked with -fopt-info-vec). Pixels without a group are computed at depth 0 (finite,
/// in the int range) and masked by w = 0.
void back_project_lanes(const RowRays& r, const float* __restrict depth, int W, float* __restrict ox, float* __restrict oy,
                        float* __restrict oz, float* __restrict ow, int32_t* __restrict cx_out, int32_t* __restrict cy_out,
                        int32_t* __restrict cz_out) {
  constexpr float kCellLimit = 1.0e9f;  // keeps the float -> int casts defined
  for (int u = 0; u < W; ++u) {
    const float d = depth[u];
    const int usable = usable_depth(d, r.min_range, r.max_range);
    const float z = usable ? d : 0.0f;
    const float x_factor = (static_cast<float>(u) - r.cx) * r.inv_fx;
    const float px = (r.r00 * x_factor + r.q0) * z + r.tx, py = (r.r10 * x_factor + r.q1) * z + r.ty,
                pz = (r.r20 * x_factor + r.q2) * z + r.tz;
    const int32_t ix = floor_cell(std::min(std::max(px * r.inv_s, -kCellLimit), kCellLimit));
    const int32_t iy = floor_cell(std::min(std::max(py * r.inv_s, -kCellLimit), kCellLimit));
    const int32_t iz = floor_cell(std::min(std::max(pz * r.inv_s, -kCellLimit), kCellLimit));
    const uint32_t out_of_range = key_range_excess(ix, iy, iz);
    const float inv_z2 = 1.0f / std::max(z * z, 1.0e-12f);  // = 1/z^2 where used; finite at z = 0
    ox[u] = px, oy[u] = py, oz[u] = pz;
    cx_out[u] = ix, cy_out[u] = iy, cz_out[u] = iz;
    ow[u] = (usable && out_of_range == 0) ? inv_z2 : 0.0f;
  }
}

/// Back-projects row v of the depth image: each pixel's world point p = t_wc + z R_wc
/// ((u - cx) / fx, (v - cy) / fy, 1), its voxel and B6 weight.
void back_project_row(const FrameSetup& f, const float* depth, int v, RowPoints& out) {
  const int W = f.width;
  for (auto* a : {&out.x, &out.y, &out.z, &out.w}) a->resize(W);
  for (auto* a : {&out.vx, &out.vy, &out.vz}) a->resize(W);
  const float y_factor = (static_cast<float>(v) - f.cy) / f.fy;
  const Eigen::Vector3f ray0 = f.R_wc.col(1) * y_factor + f.R_wc.col(2);
  const RowRays rays{f.R_wc(0, 0), f.R_wc(1, 0), f.R_wc(2, 0), ray0.x(), ray0.y(), ray0.z(),
                     f.t_wc.x(), f.t_wc.y(), f.t_wc.z(), f.cx, 1.0f / f.fx, 1.0f / f.s, f.min_range, f.max_range};
  back_project_lanes(rays, depth, W, out.x.data(), out.y.data(), out.z.data(), out.w.data(), out.vx.data(), out.vy.data(),
                     out.vz.data());
}

// =============================================================================================
// Grouped ray casting (METHODS B5 + B6)
// =============================================================================================
class GroupedIntegrator final : public ArenaIntegrator {
 public:
  explicit GroupedIntegrator(const TsdfConfig& cfg) : ArenaIntegrator(cfg) {}
  std::string name() const override { return "grouped"; }

 private:
  /// A pixel's group (in its strip's table, -1 = no group) and weight, kept only for the
  /// per-pixel probabilities: writing every pixel's point was 10 MB a VGA frame.
  struct PixelGroup {
    int32_t group;
    float w;
  };
  struct LabelSlot {
    Eigen::Vector3f weighted_sum = Eigen::Vector3f::Zero();
    float weight = 0, confidence_sum = 0;
    float rgb_sum[3] = {0, 0, 0};
    ClassId label = 0;
    int32_t next = -1;
    void add(const LabelSlot& o) {
      weight += o.weight, weighted_sum += o.weighted_sum, confidence_sum += o.confidence_sum;
      for (int c = 0; c < 3; ++c) rgb_sum[c] += o.rgb_sum[c];
    }
  };
  /// A LabelSlot's running sums, held in registers by the grouping loop.
  struct SlotSums {
    float weight = 0, x = 0, y = 0, z = 0, confidence = 0, r = 0, g = 0, b = 0;
    void load(const LabelSlot& s) {
      weight = s.weight, x = s.weighted_sum.x(), y = s.weighted_sum.y(), z = s.weighted_sum.z();
      confidence = s.confidence_sum, r = s.rgb_sum[0], g = s.rgb_sum[1], b = s.rgb_sum[2];
    }
    void store(LabelSlot& s) const {
      s.weight = weight, s.weighted_sum = Eigen::Vector3f(x, y, z), s.confidence_sum = confidence;
      s.rgb_sum[0] = r, s.rgb_sum[1] = g, s.rgb_sum[2] = b;
    }
  };
  /// What grouping reads and writes of a group, 16 bytes (it touches one per change of voxel;
  /// with the rest of Group, 100 bytes, they were its cache misses).
  struct GroupHead {
    uint64_t key;
    int32_t first_slot;
    float total_weight;
  };
  /// Voxel groups with per-label sums (B5), found by voxel key: one table per strip of rows,
  /// and the frame's, merged from them.
  struct GroupTable {
    std::vector<int32_t> table;  ///< open addressing, group ids, -1 = empty
    std::vector<GroupHead> heads;
    std::vector<LabelSlot> slots;
    /// Empties it, the hash sized for at least `capacity` (a power of two >= 1024; not 2x
    /// the pixels: a table that size was a 4 MB fill and a cache miss per probe).
    void reset(size_t capacity) {
      size_t n = 1024;
      while (n < capacity) n *= 2;
      table.assign(n, -1);
      heads.clear();
      slots.clear();
    }
    /// The group of voxel key `key`, a new one (the next id) when absent; doubles at half load.
    int32_t find_or_add_group(uint64_t key) {
      size_t mask = table.size() - 1;
      for (size_t h = mix_key(key) & mask;; h = (h + 1) & mask) {
        const int32_t g = table[h];
        if (g >= 0 && heads[g].key == key) return g;
        if (g >= 0) continue;
        const int32_t added = static_cast<int32_t>(heads.size());
        heads.push_back(GroupHead{key, -1, 0.0f});
        if (2 * heads.size() <= table.size()) {
          table[h] = added;
          return added;
        }
        table.assign(2 * table.size(), -1);  // grow: re-insert every group, the new one too
        mask = table.size() - 1;
        for (size_t k = 0; k < heads.size(); ++k) {
          size_t j = mix_key(heads[k].key) & mask;
          while (table[j] >= 0) j = (j + 1) & mask;
          table[j] = static_cast<int32_t>(k);
        }
        return added;
      }
    }
    /// The slot of `label` in group g's list, a new one appended when absent.
    int32_t find_or_add_slot(int32_t g, ClassId label) {
      int32_t s = heads[g].first_slot, last = -1;
      while (s >= 0 && slots[s].label != label) {
        last = s;
        s = slots[s].next;
      }
      if (s >= 0) return s;
      s = static_cast<int32_t>(slots.size());
      slots.emplace_back();
      slots.back().label = label;
      if (last < 0) heads[g].first_slot = s;
      else slots[last].next = s;
      return s;
    }
  };
  /// Rows [v0, v1) of the frame, grouped on their own (in parallel with the other strips).
  /// The strips are fixed by the image, not by the thread count: the map does not depend on it.
  static constexpr int kStripRows = 64;
  struct Strip {
    int v0 = 0, v1 = 0;
    size_t valid_pixels = 0;
    GroupTable groups;
    std::vector<int32_t> frame_group;  ///< per strip group, its id in the frame's table
    RowPoints row;                     ///< the row being grouped
  };
  /// The rest, filled after grouping (same index).
  struct Group {
    Eigen::Vector3f point;
    ClassId label;
    Rgb8 colour;
    ClassDistribution observation;
  };
  /// Consecutive updates of one chunk in one block.
  struct BlockRun {
    BlockIndex block;
    uint32_t count;
    int32_t slot;   ///< the block's index among the frame's touched blocks
    Block* found;   ///< the block if it existed before this frame (looked up in parallel)
  };
  /// One voxel update of a ray, its voxel by the local index within its block (the block is
  /// its run's).
  struct BlockUpdate {
    float d;
    int32_t group;
    uint16_t li;
  };
  /// A run of one block's updates where step 4 wrote them.
  struct RunRef {
    const BlockUpdate* first;
    size_t count;
  };
  /// What a voxel update reads of its ray (group), 8 bytes: the apply loop's reads of the
  /// 100-byte groups were its cache misses.
  struct RayInfo {
    float weight;
    Rgb8 colour;
    ClassId label;
  };
  /// What the per-block apply step of one frame reads.
  struct ApplyPass {
    const VoxelUpdater& updater;
    const RunRef* runs;
    const size_t* offsets;  ///< block k's runs: [offsets[k], offsets[k + 1])
    const RayInfo* rays;
    const Group* groups;
    float label_band;
    bool labels, colour, observation;
  };

  void run(TsdfMap& map, const IntegrationInput& in, const FrameSetup& f) override {
    // 1-2. Back-project and group by voxel, per strip of rows (parallel), then merge (serial).
    group_pixels(in, f);
    // 3. Each group's label = argmax W_l, its point = weighted mean of the points with that label.
    const bool want_observation = map.has_bayes_layer() && f.labels;
    const std::vector<GroupHead>& heads = frame_.heads;
    // Reused from the last frame: every field read later is written below (an observation only
    // where it is read: labelled groups with the Bayes layer).
    groups_.resize(heads.size());
    ray_info_.resize(heads.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, heads.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t k = r.begin(); k < r.end(); ++k) summarise_group(f, want_observation, k);
    });
    if (want_observation && f.probabilities) group_probabilities(in, f, map.bayes().k());
    // 4. Cast one ray per group through the truncation band (parallel in fixed chunks).
    constexpr size_t kChunk = 512;
    const size_t n_chunks = (groups_.size() + kChunk - 1) / kChunk;
    chunk_updates_.resize(n_chunks);
    chunk_runs_.resize(n_chunks);
    const float delta = f.delta;
    tbb::parallel_for(size_t{0}, n_chunks, [&](size_t c) {
      // The chunk's updates, by local index, as runs of one block (step 5 touches each run,
      // not each update, and copies the runs).
      std::vector<BlockUpdate>& out = chunk_updates_[c];
      std::vector<BlockRun>& runs = chunk_runs_[c];
      out.clear();
      runs.clear();
      RayCells cells;
      const size_t end = std::min(groups_.size(), (c + 1) * kChunk);
      for (size_t g = c * kChunk; g < end; ++g) {
        const Eigen::Vector3f ray = groups_[g].point - f.t_wc;
        const float dist = ray.norm();
        if (!(dist > 0)) continue;
        const Eigen::Vector3f dir = ray / dist;
        const Eigen::Vector3f a = f.t_wc + dir * std::max(0.0f, dist - delta);
        const Eigen::Vector3f b = f.t_wc + dir * (dist + delta);
        cells.clear();
        traverse_cells(a / f.s, b / f.s, [&](const Eigen::Vector3i& vox) { cells.add(vox); });
        cells.distances(dist, f.s, f.t_wc);
        for (size_t j = 0; j < cells.size(); ++j) {
          if (cells.d[j] <= -delta) continue;
          const VoxelIndex voxel = cells.voxel(j);
          const BlockIndex b = block_of_voxel(voxel);
          if (runs.empty() || runs.back().block != b) runs.push_back(BlockRun{b, 0, -1, find_existing(map, runs, b)});
          ++runs.back().count;
          out.push_back(BlockUpdate{cells.d[j], static_cast<int32_t>(g), static_cast<uint16_t>(local_index(voxel))});
        }
      }
    });
    // 5. Touch the blocks per run in ray order, then bucket the runs by block, stable (a
    // counting sort; each block's runs in ray order). The updates stay where step 4 wrote them.
    TouchedBlocks touched;
    touched.stamp = map.next_frame_stamp();
    size_t n_updates = 0;
    for (auto& runs : chunk_runs_)
      for (BlockRun& run : runs) run.slot = touched.touch(map, run.block, run.found), n_updates += run.count;
    const size_t n_blocks = touched.blocks.size();
    bucket_runs(n_blocks);
    // 6. Apply per block in parallel (each block's updates in ray order: deterministic).
    const VoxelUpdater updater = make_updater(map, f);
    const ApplyPass pass{updater,
                         block_runs_.data(),
                         offsets_.data(),
                         ray_info_.data(),
                         groups_.data(),
                         f.label_band,
                         f.labels && (map.has_label_layer() || map.has_bayes_layer()),
                         f.colour && map.has_colour_layer(),
                         want_observation};
    const bool avx2 = have_avx2_f16c();
    tbb::parallel_for(size_t{0}, n_blocks, [&](size_t k) {
      Block& block = *touched.blocks[k];
      if (avx2) apply_block_avx2(block, k, pass);
      else apply_block_sse2(block, k, pass);
      block.mesh_dirty = true;
    });
    stats_.voxel_updates = n_updates;
    stats_.touched_blocks = n_blocks;
    stats_.allocated_blocks = touched.allocated;
  }

  /// Block b of a new run, looked up while the map is only read (step 4, in parallel; the
  /// serial step 5 then only allocates what is missing): a chunk's rays are neighbours, so it
  /// is mostly the block of one of the chunk's last runs.
  static Block* find_existing(TsdfMap& map, const std::vector<BlockRun>& runs, const BlockIndex& b) {
    constexpr size_t kRecent = 4;
    for (size_t i = runs.size(); i > 0 && i + kRecent > runs.size(); --i)
      if (runs[i - 1].block == b) return runs[i - 1].found;
    return map.find_block(b);
  }

  /// block_runs_: the runs of every chunk by block slot, each block's in ray order (stable
  /// counting sort), block k's at [offsets_[k], offsets_[k + 1]).
  void bucket_runs(size_t n_blocks) {
    offsets_.assign(n_blocks + 1, 0);
    for (const auto& runs : chunk_runs_)
      for (const BlockRun& run : runs) ++offsets_[run.slot + 1];
    for (size_t k = 0; k < n_blocks; ++k) offsets_[k + 1] += offsets_[k];
    cursors_.assign(offsets_.begin(), offsets_.end() - 1);
    block_runs_.resize(offsets_.back());
    for (size_t c = 0; c < chunk_runs_.size(); ++c) {
      const BlockUpdate* u = chunk_updates_[c].data();
      for (const BlockRun& run : chunk_runs_[c]) {
        block_runs_[cursors_[run.slot]++] = RunRef{u, run.count};
        u += run.count;
      }
    }
  }

  /// Back-projects and groups the pixels of every strip (parallel), then merges the strips.
  void group_pixels(const IntegrationInput& in, const FrameSetup& f) {
    const int n_strips = (f.height + kStripRows - 1) / kStripRows;
    if (f.probabilities) pixel_groups_.assign(static_cast<size_t>(f.width) * f.height, PixelGroup{-1, 0.0f});
    strips_.resize(n_strips);
    tbb::parallel_for(0, n_strips, [&](int k) {
      group_strip(in, f, k * kStripRows, std::min(f.height, (k + 1) * kStripRows), strips_[k]);
    });
    merge_strips();
    for (const Strip& strip : strips_) stats_.valid_pixels += strip.valid_pixels;
    stats_.rays = frame_.heads.size();
  }

  /// Rows [v0, v1): each row back-projected, then its pixels grouped by voxel in pixel order
  /// (B5). The current group's weight and label slot's sums are held in registers while
  /// consecutive pixels add to them (written back when the pixel's voxel or label changes): the
  /// same additions in the same order as into memory, without a store-forwarded load on each chain.
  void group_strip(const IntegrationInput& in, const FrameSetup& f, int v0, int v1, Strip& strip) {
    GroupTable& t = strip.groups;
    t.reset(4 * t.heads.size());
    strip.v0 = v0, strip.v1 = v1, strip.valid_pixels = 0;
    RowPoints& row = strip.row;
    uint64_t last_key = ~0ULL;
    int32_t g = -1, s = -1;
    ClassId last_label = 0;
    float group_weight = 0;
    SlotSums sums;
    for (int v = v0; v < v1; ++v) {
      back_project_row(f, in.depth.ptr<float>(v), v, row);
      const uint8_t* labels = f.labels ? in.labels.ptr<uint8_t>(v) : nullptr;
      const float* confidence = f.confidence ? in.confidence.ptr<float>(v) : nullptr;
      const uint8_t* colour = f.colour ? in.colour.ptr<uint8_t>(v) : nullptr;
      for (int u = 0; u < f.width; ++u) {
        const float w = row.w[u];
        if (w == 0) continue;
        ++strip.valid_pixels;
        const ClassId label = labels ? labels[u] : 0;
        const uint64_t key = row.key(u);
        const bool same_group = key == last_key;  // neighbouring pixels mostly fall into the same voxel
        if (!same_group || label != last_label) {
          if (s >= 0) sums.store(t.slots[s]);
          if (!same_group) {
            if (g >= 0) t.heads[g].total_weight = group_weight;
            g = t.find_or_add_group(key);
            last_key = key;
            group_weight = t.heads[g].total_weight;
          }
          s = t.find_or_add_slot(g, label);
          sums.load(t.slots[s]);
          last_label = label;
        }
        if (f.probabilities) pixel_groups_[static_cast<size_t>(v) * f.width + u] = PixelGroup{g, w};
        group_weight += w;
        sums.weight += w;
        sums.x += w * row.x[u], sums.y += w * row.y[u], sums.z += w * row.z[u];
        if (confidence) sums.confidence += w * confidence[u];
        if (colour) {
          const uint8_t* bgr = colour + 3 * u;
          sums.r += w * bgr[2], sums.g += w * bgr[1], sums.b += w * bgr[0];
        }
      }
    }
    if (s >= 0) sums.store(t.slots[s]);
    if (g >= 0) t.heads[g].total_weight = group_weight;
  }

  /// The strips' groups into the frame's, strip after strip: group ids follow the first
  /// appearance in pixel order, as one serial pass gives; a group's sums add per strip.
  void merge_strips() {
    size_t strip_groups = 0;
    for (const Strip& strip : strips_) strip_groups += strip.groups.heads.size();
    frame_.reset(2 * strip_groups);  // at most half full: it never grows
    for (Strip& strip : strips_) {
      const GroupTable& t = strip.groups;
      strip.frame_group.resize(t.heads.size());
      for (size_t k = 0; k < t.heads.size(); ++k) {
        const int32_t g = frame_.find_or_add_group(t.heads[k].key);
        strip.frame_group[k] = g;
        frame_.heads[g].total_weight += t.heads[k].total_weight;
        for (int32_t s = t.heads[k].first_slot; s >= 0; s = t.slots[s].next)
          frame_.slots[frame_.find_or_add_slot(g, t.slots[s].label)].add(t.slots[s]);
      }
    }
  }

  /// Group k's label = argmax W_l, its point = the weighted mean of the points with that label
  /// (B5), colour and observation likewise; and what its ray's voxel updates read.
  void summarise_group(const FrameSetup& f, bool want_observation, size_t k) {
    Group& g = groups_[k];
    const LabelSlot* best = nullptr;
    for (int32_t s = frame_.heads[k].first_slot; s >= 0; s = frame_.slots[s].next) {
      const LabelSlot& slot = frame_.slots[s];
      if (!best || slot.weight > best->weight || (slot.weight == best->weight && slot.label < best->label)) best = &slot;
    }
    g.label = best->label;
    g.point = best->weighted_sum / best->weight;
    g.colour = Rgb8{static_cast<uint8_t>(std::lround(best->rgb_sum[0] / best->weight)),
                    static_cast<uint8_t>(std::lround(best->rgb_sum[1] / best->weight)),
                    static_cast<uint8_t>(std::lround(best->rgb_sum[2] / best->weight))};
    if (want_observation && g.label != 0 && !f.probabilities) {
      const float c = f.confidence ? std::clamp(best->confidence_sum / best->weight, 0.01f, 0.999f) : f.default_confidence;
      g.observation = ClassDistribution::from_label(g.label, c, f.confusion_classes);
    }
    ray_info_[k] = RayInfo{frame_.heads[k].total_weight, g.colour, g.label};
  }

  /// B6 for the updates of block k in ray order, then one label observation per voxel, from the
  /// ray whose surface point is nearest.
  template <bool kNativeHalf>
  [[gnu::always_inline]] static void apply_block(Block& block, size_t k, const ApplyPass& p) {
    std::array<float, kBlockVoxels> best_d;
    std::array<int32_t, kBlockVoxels> best_group;
    if (p.labels) best_group.fill(-1);
    for (size_t r = p.offsets[k]; r < p.offsets[k + 1]; ++r) {
      // The runs lie where each chunk wrote them (a jump per run): the next one's first
      // updates are fetched while this one is applied.
      if (r + 1 < p.offsets[k + 1]) __builtin_prefetch(p.runs[r + 1].first);
      for (const BlockUpdate& u : std::span(p.runs[r].first, p.runs[r].count)) {
        const RayInfo& ray = p.rays[u.group];
        const int li = u.li;
        if (!p.updater.update<kNativeHalf>(block, li, u.d, ray.weight, 0, nullptr, p.colour ? &ray.colour : nullptr)) continue;
        if (p.labels && ray.label != 0 && std::fabs(u.d) <= p.label_band && (best_group[li] < 0 || std::fabs(u.d) < best_d[li])) {
          best_group[li] = u.group;
          best_d[li] = std::fabs(u.d);
        }
      }
    }
    if (p.labels)
      for (int li = 0; li < kBlockVoxels; ++li)
        if (best_group[li] >= 0) {
          const Group& g = p.groups[best_group[li]];
          p.updater.update_labels(block, li, g.label, p.observation ? &g.observation : nullptr);
        }
  }
  /// Baseline and AVX2+F16C builds, as the projective integrator's integrate_block_*.
  static void apply_block_sse2(Block& block, size_t k, const ApplyPass& p) { apply_block<false>(block, k, p); }
  SEMAP_TARGET_AVX2 static void apply_block_avx2(Block& block, size_t k, const ApplyPass& p) {
    apply_block<true>(block, k, p);
  }

  /// Bayesian observation of a group from per-pixel probabilities: the weighted mean
  /// probability vector of the group's winning-label points, reduced to its top k.
  void group_probabilities(const IntegrationInput& in, const FrameSetup& f, int k) {
    const int nc = f.prob_channels;
    std::vector<float> sums(groups_.size() * nc, 0.0f);
    for (const Strip& strip : strips_) {  // pixel order
      const size_t end = static_cast<size_t>(strip.v1) * f.width;
      for (size_t i = static_cast<size_t>(strip.v0) * f.width; i < end; ++i) {
        const PixelGroup& pp = pixel_groups_[i];
        if (pp.group < 0) continue;
        const int32_t g = strip.frame_group[pp.group];
        const ClassId label = in.labels.ptr<uint8_t>(0)[i];
        if (label != groups_[g].label) continue;
        const float* probs = in.probabilities.ptr<float>(0) + i * nc;
        float* sum = &sums[static_cast<size_t>(g) * nc];
        for (int c = 0; c < nc; ++c) sum[c] += pp.w * probs[c];
      }
    }
    for (size_t g = 0; g < groups_.size(); ++g)
      if (groups_[g].label != 0) groups_[g].observation = ClassDistribution::from_probabilities(&sums[g * nc], nc, k);
  }

  std::vector<PixelGroup> pixel_groups_;  ///< only with per-pixel probabilities
  std::vector<Strip> strips_;
  GroupTable frame_;
  std::vector<Group> groups_;
  std::vector<std::vector<BlockUpdate>> chunk_updates_;
  std::vector<std::vector<BlockRun>> chunk_runs_;
  std::vector<size_t> offsets_, cursors_;
  std::vector<RunRef> block_runs_;
  std::vector<RayInfo> ray_info_;
};

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
    n += p.updater.update<kNativeHalf>(block, li, sdf, 1.0f / (depth * depth), label, obs, p.colour ? &sample.rgb : nullptr);
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

std::unique_ptr<Integrator> make_integrator(IntegratorKind kind, const TsdfConfig& config) {
  if (kind == IntegratorKind::grouped) return std::make_unique<GroupedIntegrator>(config);
  return std::make_unique<ProjectiveIntegrator>(config);
}

PointGroup group_points(const std::vector<LabelledPoint>& points) {
  PointGroup g;
  std::array<float, kNumClasses> weight{};
  for (const LabelledPoint& p : points) {
    weight[p.label] += p.weight;
    g.total_weight += p.weight;
  }
  for (int l = 0; l < kNumClasses; ++l)
    if (weight[l] > weight[g.label]) g.label = static_cast<ClassId>(l);
  g.label_weight = weight[g.label];
  Eigen::Vector3f sum = Eigen::Vector3f::Zero();
  for (const LabelledPoint& p : points)
    if (p.label == g.label) sum += p.weight * p.position;
  g.point = g.label_weight > 0 ? Eigen::Vector3f(sum / g.label_weight) : Eigen::Vector3f::Zero();
  return g;
}

}  // namespace semap
