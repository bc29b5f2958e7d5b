// 3D distance queries (issue 39): the Euclidean distance field's build time and memory on a real
// map, and the per-query time of a distance_m / is_free on it, against the query it replaced
// (the TSDF's own sdf, trilinear and clamped at the truncation band) in the same run.
//   bench_esdf --out DIR [--queries 200000] [--radius 0.3] [--repeats 3]
// DIR: a `semap run` output folder (map.semap, trajectory.txt), e.g.
//   build/semap run ../shared/data/7scenes_redkitchen --out /tmp/nav_rk --max-frames 250
// Query points: uniform in the bounding box of the camera positions grown by 1 m (where a robot
// asks). Prints one JSON object.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>

#include "bench/bench_options.hpp"
#include "semap/core/error.hpp"
#include "semap/io/trajectory_io.hpp"
#include "semap/navigation/distance_query.hpp"
#include "tsdf/map_io.hpp"
#include "tsdf/tsdf_interpolation.hpp"

namespace fs = std::filesystem;
using namespace semap;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/// The query before the distance field: the TSDF's interpolated sdf clamped at the truncation.
double clamped_tsdf_distance(CachedVoxelLookup& lookup, const TsdfMap& map, const Eigen::Vector3d& p) {
  float sdf = 0.f;
  if (!interpolate_sdf(lookup, p.cast<float>(), sdf)) return std::numeric_limits<double>::quiet_NaN();
  const double t = map.config().truncation();
  return std::clamp(static_cast<double>(sdf), -t, t);
}

}  // namespace

int main(int argc, char** argv) {
  fs::path out;
  size_t queries = 200000;
  double radius_m = 0.3;
  int repeats = 3;
  const auto exit_code = bench::parse_options(
      argc, argv, 1, "--out DIR [--queries N] [--radius M] [--repeats N]", [&](const std::string& k, const std::string& v) {
        if (k == "--out") out = v;
        else if (k == "--queries") queries = std::stoul(v);
        else if (k == "--radius") radius_m = std::stod(v);
        else if (k == "--repeats") repeats = std::stoi(v);
        else return false;
        return true;
      });
  if (exit_code) return *exit_code;
  if (out.empty()) {
    std::cerr << "bench_esdf: --out DIR (a semap run output folder) is required\n";
    return 2;
  }
  try {
    const TsdfMap map = load_map(out / "map.semap");
    std::vector<Eigen::Vector3d> cameras;
    for (const StampedPose& p : read_tum_trajectory(out / "trajectory.txt")) cameras.push_back(p.T_world_camera.translation());
    if (cameras.empty()) throw Error(out / "trajectory.txt", "no poses");
    Eigen::AlignedBox3d box;
    for (const Eigen::Vector3d& c : cameras) box.extend(c);
    std::mt19937 rng(1);
    std::vector<Eigen::Vector3d> points(queries);
    for (Eigen::Vector3d& p : points)
      for (int i = 0; i < 3; ++i)
        p[i] = std::uniform_real_distribution<double>(box.min()[i] - 1.0, box.max()[i] + 1.0)(rng);

    nlohmann::json runs = nlohmann::json::array();
    for (int r = 0; r < repeats; ++r) {
      auto t0 = Clock::now();
      const DistanceQuery query(map, NavigationConfig{}, cameras);
      const double build_s = seconds_since(t0);
      double sum = 0;
      size_t observed = 0, beyond_truncation = 0, free = 0;
      t0 = Clock::now();
      for (const Eigen::Vector3d& p : points) {
        const double d = query.distance_m(p);
        if (std::isnan(d)) continue;
        ++observed, sum += d;
        beyond_truncation += std::abs(d) > map.config().truncation();
      }
      const double esdf_query_ns = 1e9 * seconds_since(t0) / queries;
      t0 = Clock::now();
      for (const Eigen::Vector3d& p : points) free += query.is_free(p, radius_m);
      const double is_free_ns = 1e9 * seconds_since(t0) / queries;
      CachedVoxelLookup lookup(map);
      size_t clamp_observed = 0;
      t0 = Clock::now();
      for (const Eigen::Vector3d& p : points) {
        const double d = clamped_tsdf_distance(lookup, map, p);
        if (!std::isnan(d)) ++clamp_observed, sum += d;
      }
      const double clamp_query_ns = 1e9 * seconds_since(t0) / queries;
      const EsdfStats& st = query.esdf().stats();
      runs.push_back({{"esdf_build_s", build_s},
                      {"esdf_cells", {st.dims.x(), st.dims.y(), st.dims.z()}},
                      {"esdf_cell_m", st.cell_m},
                      {"esdf_build_peak_mb", st.peak_bytes / 1e6},
                      {"esdf_held_mb", query.esdf().memory_bytes() / 1e6},
                      {"cameras_used", st.cameras_used},
                      {"carved_blocks", st.carved_blocks},
                      {"shadow_cells", st.shadow_cells},
                      {"esdf_query_ns", esdf_query_ns},
                      {"is_free_ns", is_free_ns},
                      {"clamped_tsdf_query_ns", clamp_query_ns},
                      {"observed_share_esdf", static_cast<double>(observed) / queries},
                      {"observed_share_clamped_tsdf", static_cast<double>(clamp_observed) / queries},
                      {"beyond_truncation_share", static_cast<double>(beyond_truncation) / queries},
                      {"free_share", static_cast<double>(free) / queries},
                      {"checksum", sum}});
    }
    nlohmann::json result = {{"map", (out / "map.semap").string()},
                             {"blocks", map.num_blocks()},
                             {"tsdf_mb", map.memory_bytes() / 1e6},
                             {"voxel_m", map.voxel_size()},
                             {"queries", queries},
                             {"radius_m", radius_m},
                             {"runs", runs}};
    std::cout << result.dump(2) << "\n";
    return 0;
  } catch (const Error& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
}
