#include "semap/navigation/esdf.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <unordered_set>

#include "semap/core/error.hpp"
#include "tsdf/tsdf_interpolation.hpp"

namespace semap {
namespace {

enum class Cell : uint8_t { kUnknown, kFree, kOccupied };
constexpr int kMaxCoarsening = 16;
constexpr float kInf = std::numeric_limits<float>::infinity();

/// Inclusive box of global indices.
struct IndexBox {
  Eigen::Vector3i lo = Eigen::Vector3i::Constant(std::numeric_limits<int>::max());
  Eigen::Vector3i hi = Eigen::Vector3i::Constant(std::numeric_limits<int>::min());
  void add(const Eigen::Vector3i& i) { lo = lo.cwiseMin(i), hi = hi.cwiseMax(i); }
  bool empty() const { return (hi.array() < lo.array()).any(); }
  Eigen::Vector3i dims() const { return hi - lo + Eigen::Vector3i::Ones(); }
  size_t size() const { return empty() ? 0 : static_cast<size_t>(dims().cast<int64_t>().prod()); }
  bool contains(const Eigen::Vector3i& i) const { return (i.array() >= lo.array()).all() && (i.array() <= hi.array()).all(); }
  size_t linear(const Eigen::Vector3i& i) const {
    const Eigen::Vector3i d = dims(), r = i - lo;
    return static_cast<size_t>(r.x()) + static_cast<size_t>(d.x()) * (r.y() + static_cast<size_t>(d.y()) * r.z());
  }
};

/// Camera positions at least kCarveCameraSpacingM apart (greedy, in trajectory order).
std::vector<Eigen::Vector3f> thin_cameras(std::span<const Eigen::Vector3d> positions) {
  std::vector<Eigen::Vector3f> kept;
  const float spacing2 = static_cast<float>(kCarveCameraSpacingM * kCarveCameraSpacingM);
  for (const Eigen::Vector3d& p : positions) {
    if (!p.allFinite()) continue;
    const Eigen::Vector3f q = p.cast<float>();
    bool near = false;
    for (const Eigen::Vector3f& k : kept) near = near || (k - q).squaredNorm() < spacing2;
    if (!near) kept.push_back(q);
  }
  return kept;
}

/// One surface voxel per allocated block: the observed voxel of smallest |sdf| under a voxel.
std::vector<Eigen::Vector3f> surface_targets(const TsdfMap& map) {
  std::vector<Eigen::Vector3f> targets;
  for (const Block* b : map.sorted_blocks()) {
    int best = -1;
    float best_abs = map.voxel_size();
    for (int i = 0; i < kBlockVoxels; ++i) {
      const TsdfVoxel& v = b->voxels[i];
      if (v.weight_q == 0 || !(std::abs(v.sdf()) < best_abs)) continue;
      best = i, best_abs = std::abs(v.sdf());
    }
    if (best < 0) continue;
    const VoxelIndex v = b->index * kBlockSide + VoxelIndex(best & 7, (best >> 3) & 7, best >> 6);
    targets.push_back(map.voxel_centre(v));
  }
  return targets;
}

/// Amanatides-Woo over the unit cells of segment a -> b (cell units): visit(cell, t_in, t_out)
/// with t in [0, 1] along the segment; stops when visit returns false.
template <class Visit>
void traverse(const Eigen::Vector3f& a, const Eigen::Vector3f& b, Visit&& visit) {
  const Eigen::Vector3f dir = b - a;
  Eigen::Vector3i cell = a.array().floor().cast<int>(), step;
  Eigen::Vector3f t_max, t_delta;
  for (int i = 0; i < 3; ++i) {
    step[i] = dir[i] > 0 ? 1 : (dir[i] < 0 ? -1 : 0);
    t_max[i] = step[i] == 0 ? kInf : (static_cast<float>(cell[i] + (step[i] > 0)) - a[i]) / dir[i];
    t_delta[i] = step[i] == 0 ? kInf : static_cast<float>(step[i]) / dir[i];
  }
  float t = 0.f;
  while (t < 1.f) {
    int axis = 0;
    if (t_max[1] < t_max[axis]) axis = 1;
    if (t_max[2] < t_max[axis]) axis = 2;
    const float t_out = std::min(t_max[axis], 1.f);
    if (!visit(cell, t, t_out)) return;
    t = t_out;
    cell[axis] += step[axis];
    t_max[axis] += t_delta[axis];
  }
}

/// Looked-through blocks (see esdf.hpp): flags over `blocks`, set from each camera-to-target
/// segment that crosses no observed surface.
std::vector<uint8_t> carve_blocks(const TsdfMap& map, const IndexBox& blocks, const std::vector<Eigen::Vector3f>& cameras,
                                  const std::vector<Eigen::Vector3f>& targets, EsdfStats& stats) {
  std::vector<uint8_t> carved(blocks.size(), 0);
  const float block_m = map.block_size(), voxel_m = map.voxel_size();
  const float max_range = static_cast<float>(map.config().max_depth);
  const float stop_before_m = 2.f * static_cast<float>(map.config().truncation());  // grazing near the target
  std::atomic<size_t> lines{0}, blocked{0};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, targets.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
    CachedVoxelLookup lookup(map);
    std::vector<size_t> marks;
    size_t n_lines = 0, n_blocked = 0;
    for (size_t ti = r.begin(); ti < r.end(); ++ti)
      for (const Eigen::Vector3f& c : cameras) {
        const Eigen::Vector3f& target = targets[ti];
        const float length = (target - c).norm();
        if (!(length <= max_range) || length <= stop_before_m) continue;
        const float t_stop = 1.f - stop_before_m / length;
        const BlockIndex target_block = map.voxel_of_point(target).array().unaryExpr([](int v) { return v >> 3; });
        bool is_blocked = false;
        marks.clear();
        traverse(c / block_m, target / block_m, [&](const Eigen::Vector3i& b, float t_in, float t_out) {
          if (t_in >= t_stop || b == target_block) return false;
          if (!map.find_block(b)) {
            if (blocks.contains(b)) marks.push_back(blocks.linear(b));
            return true;
          }
          // An allocated block: any observed voxel behind a surface on the way blocks the line.
          const float t_end = std::min(t_out, t_stop);
          const float dt = 0.5f * voxel_m / length;
          for (float t = t_in; t < t_end && !is_blocked; t += dt) {
            const TsdfVoxel* v = lookup.observed(map.voxel_of_point(c + t * (target - c)));
            is_blocked = v && !(v->sdf() > 0.f);
          }
          return !is_blocked;
        });
        ++n_lines;
        if (is_blocked) {
          ++n_blocked;
          continue;
        }
        for (size_t m : marks) std::atomic_ref<uint8_t>(carved[m]).store(1, std::memory_order_relaxed);
      }
    lines += n_lines, blocked += n_blocked;
  });
  stats.lines_of_sight = lines, stats.blocked_lines = blocked;
  return carved;
}

/// Consecutive camera positions farther apart than this are a jump (relocalisation, a gap in
/// the frames), not a path the camera moved along.
constexpr double kMaxPathStepM = 0.5;

/// The camera's path is free space too: the unallocated blocks along the segments between
/// consecutive camera positions (every one, not only the thinned ones; after a jump only the
/// position itself).
void carve_path(const TsdfMap& map, const IndexBox& blocks, std::span<const Eigen::Vector3d> positions,
                std::vector<uint8_t>& carved) {
  const float block_m = map.block_size();
  auto carve = [&](const Eigen::Vector3i& blk) {
    if (!map.find_block(blk) && blocks.contains(blk)) carved[blocks.linear(blk)] = 1;
  };
  const Eigen::Vector3d* previous = nullptr;
  for (const Eigen::Vector3d& p : positions) {
    if (!p.allFinite()) continue;
    const bool step = previous && (*previous - p).norm() <= kMaxPathStepM;
    const Eigen::Vector3f a = (step ? *previous : p).cast<float>() / block_m, b = p.cast<float>() / block_m;
    traverse(a, a == b ? Eigen::Vector3f(b + Eigen::Vector3f::Constant(1e-4f)) : b, [&](const Eigen::Vector3i& blk, float, float) {
      carve(blk);
      return true;
    });
    previous = &p;
  }
}

/// Felzenszwalb-Huttenlocher 1D transform of one line with nearest-site tracking: in
/// f (squared distance so far, inf: none) and site (its site), out the same after this axis.
struct LinePass {
  std::vector<float> f, z;
  std::vector<int32_t> site, v;
  std::vector<float> out_f;
  std::vector<int32_t> out_site;
  void run(int n) {
    v.resize(n), z.resize(n + 1), out_f.resize(n), out_site.resize(n);
    int k = -1;
    for (int q = 0; q < n; ++q) {
      if (f[q] == kInf) continue;
      const float fq = f[q] + static_cast<float>(q) * q;
      float s = -kInf;
      while (k >= 0) {
        const int p = v[k];
        s = (fq - (f[p] + static_cast<float>(p) * p)) / (2.f * (q - p));
        if (s > z[k]) break;
        --k;
      }
      ++k;
      v[k] = q;
      z[k] = k == 0 ? -kInf : s;
      z[k + 1] = kInf;
    }
    if (k < 0) {
      std::fill(out_f.begin(), out_f.end(), kInf);
      std::fill(out_site.begin(), out_site.end(), -1);
      return;
    }
    int j = 0;
    for (int q = 0; q < n; ++q) {
      while (z[j + 1] < static_cast<float>(q)) ++j;
      const int p = v[j];
      out_f[q] = static_cast<float>(q - p) * (q - p) + f[p];
      out_site[q] = site[p];
    }
  }
};

/// One axis of the 3D transform over every line along it.
void transform_axis(std::vector<float>& g, std::vector<int32_t>& site, const Eigen::Vector3i& dims, int axis) {
  const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
  const size_t stride[3] = {1, static_cast<size_t>(dims.x()), static_cast<size_t>(dims.x()) * dims.y()};
  const int n = dims[axis];
  tbb::parallel_for(tbb::blocked_range<int>(0, dims[a2]), [&](const tbb::blocked_range<int>& r) {
    LinePass line;
    line.f.resize(n), line.site.resize(n);
    for (int i2 = r.begin(); i2 < r.end(); ++i2)
      for (int i1 = 0; i1 < dims[a1]; ++i1) {
        const size_t base = i1 * stride[a1] + i2 * stride[a2];
        for (int q = 0; q < n; ++q) line.f[q] = g[base + q * stride[axis]], line.site[q] = site[base + q * stride[axis]];
        line.run(n);
        for (int q = 0; q < n; ++q) g[base + q * stride[axis]] = line.out_f[q], site[base + q * stride[axis]] = line.out_site[q];
      }
  });
}

size_t linear_index(const Eigen::Vector3i& c, const Eigen::Vector3i& dims) {
  return static_cast<size_t>(c.x()) + static_cast<size_t>(dims.x()) * (c.y() + static_cast<size_t>(dims.y()) * c.z());
}

/// The grid's view of the map: each cell's sdf from the TSDF voxel at its centre, or the
/// truncation for looked-through cells of unallocated blocks and for unobserved cells on the
/// camera's path.
struct CellReader {
  const TsdfMap& map;
  const IndexBox& blocks;
  const std::vector<uint8_t>& carved;
  const std::unordered_set<size_t>& path_cells;
  const Esdf& grid;
  float truncation;
  /// False when the cell is unknown.
  bool sdf(CachedVoxelLookup& lookup, const Eigen::Vector3i& cell, float& sdf_m) const {
    const VoxelIndex v = map.voxel_of_point(grid.cell_centre_W(cell).cast<float>());
    if (const TsdfVoxel* voxel = lookup.observed(v)) return sdf_m = voxel->sdf(), true;
    const BlockIndex b = block_of_voxel(v);
    const bool looked_through = !map.find_block(b) && blocks.contains(b) && carved[blocks.linear(b)];
    if (!looked_through && !path_cells.contains(linear_index(cell, grid.dims()))) return false;
    return sdf_m = truncation, true;
  }
};

/// Cells on the camera's path (consecutive positions at most kMaxPathStepM apart) and the 8
/// around each position (a query there interpolates them).
std::unordered_set<size_t> path_cells(const Esdf& grid, const Eigen::Vector3i& origin_cell, double cell_m,
                                      std::span<const Eigen::Vector3d> positions) {
  std::unordered_set<size_t> cells;
  const Eigen::Vector3i dims = grid.dims();
  auto add = [&](const Eigen::Vector3i& c) {
    if ((c.array() >= 0).all() && (c.array() < dims.array()).all()) cells.insert(linear_index(c, dims));
  };
  auto in_cells = [&](const Eigen::Vector3d& p) { return Eigen::Vector3f((p / cell_m - origin_cell.cast<double>()).cast<float>()); };
  const Eigen::Vector3d* previous = nullptr;
  for (const Eigen::Vector3d& p : positions) {
    if (!p.allFinite()) continue;
    if (previous && (*previous - p).norm() <= kMaxPathStepM && *previous != p)
      traverse(in_cells(*previous), in_cells(p), [&](const Eigen::Vector3i& c, float, float) { return add(c), true; });
    const Eigen::Vector3f u = in_cells(p) - Eigen::Vector3f::Constant(0.5f);
    const Eigen::Vector3i c0 = u.array().floor().cast<int>();
    for (int corner = 0; corner < 8; ++corner) add(c0 + Eigen::Vector3i(corner & 1, (corner >> 1) & 1, corner >> 2));
    previous = &p;
  }
  return cells;
}

/// body(cell) over every cell, parallel over z; each range runs its own copy of body.
template <class Body>
void for_each_cell(const Eigen::Vector3i& dims, const Body& body) {
  tbb::parallel_for(tbb::blocked_range<int>(0, dims.z()), [&](const tbb::blocked_range<int>& r) {
    Body local = body;
    for (int z = r.begin(); z < r.end(); ++z)
      for (int y = 0; y < dims.y(); ++y)
        for (int x = 0; x < dims.x(); ++x) local(Eigen::Vector3i(x, y, z));
  });
}

/// Whether o is a 6-neighbour of c inside the grid (nb: 0..5).
bool neighbour(const Eigen::Vector3i& c, int nb, const Eigen::Vector3i& dims, Eigen::Vector3i& o) {
  o = c;
  o[nb / 2] += nb % 2 ? 1 : -1;
  return (o.array() >= 0).all() && (o.array() < dims.array()).all();
}

/// Shadow voxels: a voxel just behind a surface along some view's rays (in its shadow, within
/// the truncation) gets negative updates there, with the weight dropping with the depth behind
/// the surface (METHODS.md B6), while the views that see it directly make it positive. Where
/// the few shadow updates win, an occupied voxel floats in free space. Such a cell lies deeper
/// behind its "surface" than one cell edge (sdf < -edge) although a free neighbour is one edge
/// away, and holds under kShadowWeightShare of that neighbour's weight; it is taken as free.
/// (A real surface's occupied cell next to free space lies within an edge of the surface and
/// was seen at full weight.)
constexpr float kShadowWeightShare = 0.5f;
constexpr int kShadowMaxOccupiedNeighbours = 3;  ///< a surface's cells have more: its sides and the inside

/// Cell states, shadow voxels (above) made free.
std::vector<Cell> cell_states(const CellReader& reader, const Eigen::Vector3i& dims, EsdfStats& st) {
  std::vector<Cell> state(static_cast<size_t>(dims.cast<int64_t>().prod()), Cell::kUnknown);
  for_each_cell(dims, [&, lookup = CachedVoxelLookup(reader.map)](const Eigen::Vector3i& c) mutable {
    float sdf;
    if (reader.sdf(lookup, c, sdf)) state[linear_index(c, dims)] = sdf > 0.f ? Cell::kFree : Cell::kOccupied;
  });
  const float edge = static_cast<float>(st.cell_m);
  const TsdfMap& map = reader.map;
  auto voxel_at = [&](CachedVoxelLookup& lookup, const Eigen::Vector3i& c) {
    return lookup.observed(map.voxel_of_point(reader.grid.cell_centre_W(c).cast<float>()));
  };
  std::vector<size_t> shadow;
  CachedVoxelLookup lookup(map);
  for (int z = 0; z < dims.z(); ++z)
    for (int y = 0; y < dims.y(); ++y)
      for (int x = 0; x < dims.x(); ++x) {
        const Eigen::Vector3i c(x, y, z);
        if (state[linear_index(c, dims)] != Cell::kOccupied) continue;
        const TsdfVoxel* vc = voxel_at(lookup, c);
        if (!vc || !(vc->sdf() < -edge)) continue;
        float free_weight = 0.f;
        int occupied = 0;
        for (int nb = 0; nb < 6; ++nb) {
          Eigen::Vector3i o;
          if (!neighbour(c, nb, dims, o)) continue;
          const Cell so = state[linear_index(o, dims)];
          occupied += so == Cell::kOccupied;
          if (so != Cell::kFree) continue;
          if (const TsdfVoxel* vo = voxel_at(lookup, o)) free_weight = std::max(free_weight, map.weights().decode(vo->weight_q));
        }
        if (occupied <= kShadowMaxOccupiedNeighbours && map.weights().decode(vc->weight_q) < kShadowWeightShare * free_weight)
          shadow.push_back(linear_index(c, dims));
      }
  for (size_t i : shadow) state[i] = Cell::kFree;
  st.shadow_cells = shadow.size();
  for (Cell c : state) {
    st.free_cells += c == Cell::kFree;
    st.occupied_cells += c == Cell::kOccupied;
  }
  st.unknown_cells = state.size() - st.free_cells - st.occupied_cells;
  return state;
}

/// The transform's sites: known cells with a 6-neighbour of the opposite state, each with the mean of its zero crossings. g = 0 and site = its index there.
std::vector<Eigen::Vector3f> surface_sites(const CellReader& reader, const std::vector<Cell>& state,
                                           const Eigen::Vector3i& dims, std::vector<float>& g, std::vector<int32_t>& site) {
  const Esdf& e = reader.grid;
  std::vector<Eigen::Vector3f> points;
  CachedVoxelLookup lookup(reader.map);
  for (int z = 0; z < dims.z(); ++z)
    for (int y = 0; y < dims.y(); ++y)
      for (int x = 0; x < dims.x(); ++x) {
        const Eigen::Vector3i c(x, y, z);
        const Cell s = state[linear_index(c, dims)];
        if (s == Cell::kUnknown) continue;
        Eigen::Vector3f sum = Eigen::Vector3f::Zero();
        int crossings = 0;
        float sdf_c = 0.f;
        bool have_c = false;
        for (int nb = 0; nb < 6; ++nb) {
          Eigen::Vector3i o;
          if (!neighbour(c, nb, dims, o)) continue;
          const Cell so = state[linear_index(o, dims)];
          if (so == Cell::kUnknown || so == s) continue;
          if (!have_c) reader.sdf(lookup, c, sdf_c), have_c = true;
          float sdf_o = 0.f;
          reader.sdf(lookup, o, sdf_o);
          // Signs as the states say (a shadow voxel turned free keeps its negative sdf).
          const float a = s == Cell::kFree ? std::max(sdf_c, 0.f) : std::min(sdf_c, 0.f);
          const float b = so == Cell::kFree ? std::max(sdf_o, 0.f) : std::min(sdf_o, 0.f);
          const float t = a != b ? std::clamp(a / (a - b), 0.f, 1.f) : 0.5f;
          sum += ((1.f - t) * e.cell_centre_W(c) + t * e.cell_centre_W(o)).cast<float>();
          ++crossings;
        }
        if (crossings == 0) continue;
        g[linear_index(c, dims)] = 0.f;
        site[linear_index(c, dims)] = static_cast<int32_t>(points.size());
        points.push_back(sum / static_cast<float>(crossings));
      }
  return points;
}

/// Grid placement: the map's blocks and the cameras' bounding box, cells of k voxels with the
/// smallest k that fits the memory limit.
void place_grid(const TsdfMap& map, const IndexBox& blocks, const NavigationConfig& config, Eigen::Vector3i& origin,
                Eigen::Vector3i& dims, double& cell_m) {
  const double limit_bytes = config.esdf_max_memory_mb * 1024.0 * 1024.0;
  const Eigen::Vector3i voxel_lo = blocks.lo * kBlockSide, voxel_hi = (blocks.hi + Eigen::Vector3i::Ones()) * kBlockSide;
  for (int k = 1;; ++k) {
    origin = voxel_lo.unaryExpr([&](int v) { return floor_div(v, k); });
    dims = voxel_hi.unaryExpr([&](int v) { return floor_div(v - 1, k); }) - origin + Eigen::Vector3i::Ones();
    cell_m = k * static_cast<double>(map.voxel_size());
    if (static_cast<double>(dims.cast<int64_t>().prod()) * kEsdfBuildBytesPerCell <= limit_bytes) return;
    if (k == kMaxCoarsening)
      throw Error("esdf", "the map's bounding box needs more than navigation.esdf_max_memory_mb = " +
                              std::to_string(config.esdf_max_memory_mb) + " MiB even at " + std::to_string(k) +
                              " voxels per cell");
  }
}

}  // namespace

double Esdf::distance_m(const Eigen::Vector3d& p_W) const {
  if (distance_.empty() || !p_W.allFinite()) return std::numeric_limits<double>::quiet_NaN();
  const Eigen::Vector3d u = p_W / cell_m_ - origin_cell_.cast<double>() - Eigen::Vector3d::Constant(0.5);
  const Eigen::Vector3d f = u.array().floor();
  if ((f.array() < 0).any() || (f.array() + 1 > (dims_.array() - 1).cast<double>()).any())
    return std::numeric_limits<double>::quiet_NaN();
  const Eigen::Vector3i c0 = f.cast<int>();
  const Eigen::Vector3d w = u - f;
  double d = 0.0;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3i o(corner & 1, (corner >> 1) & 1, corner >> 2);
    const double weight = (o.x() ? w.x() : 1 - w.x()) * (o.y() ? w.y() : 1 - w.y()) * (o.z() ? w.z() : 1 - w.z());
    d += weight * distance_[linear(c0 + o)];  // NaN (unknown) makes the sum NaN
  }
  return d;
}

Esdf build_esdf(const TsdfMap& map, std::span<const Eigen::Vector3d> camera_positions_W, const NavigationConfig& config) {
  const auto start = std::chrono::steady_clock::now();
  Esdf e;
  e.max_distance_m_ = config.esdf_max_distance_m;
  EsdfStats& st = e.stats_;
  IndexBox blocks;
  for (const auto& b : map.blocks()) blocks.add(b->index);
  const std::vector<Eigen::Vector3f> cameras = thin_cameras(camera_positions_W);
  for (const Eigen::Vector3d& c : camera_positions_W)  // with the cells a query there interpolates
    for (int corner = 0; c.allFinite() && corner < 8; ++corner) {
      const Eigen::Vector3d o((corner & 1) ? 1 : -1, (corner & 2) ? 1 : -1, (corner & 4) ? 1 : -1);
      blocks.add(block_of_voxel(map.voxel_of_point((c + o * map.block_size()).cast<float>())));
    }
  st.cameras_used = cameras.size();
  if (blocks.empty()) return e;
  place_grid(map, blocks, config, e.origin_cell_, e.dims_, e.cell_m_);
  const Eigen::Vector3i dims = e.dims_;
  st.dims = dims, st.cell_m = e.cell_m_;
  const size_t n = static_cast<size_t>(dims.cast<int64_t>().prod());
  st.peak_bytes = n * kEsdfBuildBytesPerCell;

  std::vector<uint8_t> carved =
      cameras.empty() ? std::vector<uint8_t>(blocks.size(), 0) : carve_blocks(map, blocks, cameras, surface_targets(map), st);
  carve_path(map, blocks, camera_positions_W, carved);
  for (uint8_t f : carved) st.carved_blocks += f;
  const std::unordered_set<size_t> path = path_cells(e, e.origin_cell_, e.cell_m_, camera_positions_W);
  const CellReader reader{map, blocks, carved, path, e, static_cast<float>(map.config().truncation())};
  const std::vector<Cell> state = cell_states(reader, dims, st);
  std::vector<float> g(n, kInf);
  std::vector<int32_t> site(n, -1);
  const std::vector<Eigen::Vector3f> surface_point = surface_sites(reader, state, dims, g, site);
  st.surface_cells = surface_point.size();
  for (int axis = 0; axis < 3; ++axis) transform_axis(g, site, dims, axis);

  // Distances to the nearest site's surface point, signed by the cell's state, clamped; g's
  // memory becomes the result.
  const float max_d = static_cast<float>(e.max_distance_m_);
  for_each_cell(dims, [&](const Eigen::Vector3i& c) {
    const size_t i = linear_index(c, dims);
    if (state[i] == Cell::kUnknown) {
      g[i] = std::numeric_limits<float>::quiet_NaN();
      return;
    }
    float d = max_d;
    if (site[i] >= 0) d = std::min(max_d, (e.cell_centre_W(c).cast<float>() - surface_point[site[i]]).norm());
    g[i] = state[i] == Cell::kFree ? d : -d;
  });
  e.distance_ = std::move(g);
  st.build_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return e;
}

}  // namespace semap
