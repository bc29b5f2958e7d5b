// The grouped integrator (METHODS B5 + B6): pixels grouped per voxel, one ray per group.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <span>
#include <vector>

#include "tsdf/integrator_common.hpp"
#include "tsdf/ray_traversal.hpp"

namespace semap::integrator_detail {
namespace {

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
    const float* label_bands;  ///< per ray: FrameSetup::label_band at its group's depth
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
    label_bands_.resize(heads.size());
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
                         label_bands_.data(),
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
    label_bands_[k] = f.label_band(f.R_cw.row(2).dot(g.point - f.t_wc));
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
        if (!p.updater.update<kNativeHalf>(block, li, u.d, ray.weight, 0, 0.0f, nullptr, p.colour ? &ray.colour : nullptr))
          continue;
        if (p.labels && ray.label != 0 && std::fabs(u.d) <= p.label_bands[u.group] &&
            (best_group[li] < 0 || std::fabs(u.d) < best_d[li])) {
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
  std::vector<float> label_bands_;  ///< per group: its label band (FrameSetup::label_band)
};

}  // namespace

std::unique_ptr<Integrator> make_grouped_integrator(const TsdfConfig& config) {
  return std::make_unique<GroupedIntegrator>(config);
}

}  // namespace semap::integrator_detail
