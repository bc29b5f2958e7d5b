// Tracking benchmark (issue 4): our tracker vs Open3D RGB-D odometry (hybrid term, frame to
// frame) on the same frames in one run, plus the effect of depth repair (A1) on ATE.
// Prints one JSON object. Usage:
//   bench_tracking [DATASET_DIR] [--frames N] [--no-open3d] [--no-repair-compare]
//                  [--no-loop-compare] [--deterministic] [--out-trajectory FILE] [--threads N]
//                  [--set "key: value"]... (tracking parameters, YAML, as in the tracking: section)
//   bench_tracking --k-table [--steps 1,3,5,10|none] [--no-keyframe-rate] [--deterministic] [--no-open3d: no baselines]
//                  [--compare-verify: also ours with tracking.verify.enabled false, the pre-issue-42 judgement] [--set ...]
//     issue 16: every k-th frame of tum_fr1_rpy and 7scenes_redkitchen (TUM-layout slices of
//     links in a temp dir, tests/sequence_slices), ATE / RPE / lost / ms per frame of ours,
//     Open3D's and OpenCV's (cv::rgbd::RgbdICPOdometry) odometry on the same frames: a text
//     table on stderr, JSON on stdout. Issue 42: plus a keyframe-rate row per sequence (k "kf":
//     frames at least 25 cm or 20 deg apart by the ground truth, tests/sequence_slices
//     frames_by_motion, as a robot recording at 1-2 Hz gives); --no-keyframe-rate leaves it out.
//     Each row also prints how often each registration check failed (dense residual / spread /
//     ambiguous / under-constrained of the verified registrations).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <ctime>
#include <string>
#include <filesystem>
#include <unistd.h>
#include <vector>

#include "semap/core/error.hpp"
#include "semap/eval/trajectory_metrics.hpp"
#include "semap/io/config_loader.hpp"
#include "semap/io/dataset.hpp"
#include "semap/io/trajectory_io.hpp"
#include "tracking/tracker.hpp"

#include "bench/open3d_odometry.hpp"
#include "bench/opencv_odometry.hpp"
#include "sequence_slices.hpp"

using namespace semap;
using json = nlohmann::json;

namespace {
bool verbose = false;
double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

json evaluate(const Trajectory& gt, const Trajectory& est) {
  json j;
  const AteResult ate = compute_ate(gt, est);
  const RpeResult rpe = compute_rpe(gt, est);
  j["ate_rmse_m"] = ate.rmse;
  j["ate_matched"] = ate.matched;
  j["rpe_trans_rmse_m_per_s"] = rpe.trans_rmse_m_per_s;
  j["rpe_rot_rmse_deg_per_s"] = rpe.rot_rmse_deg_per_s;
  return j;
}

json run_ours(const std::vector<Frame>& frames, const CameraModel& camera, const TrackingConfig& config,
              const Trajectory& gt, Trajectory* out_traj) {
  Tracker tracker(config, camera);
  std::vector<double> ms;
  TrackTimings sum;  // per-part means (issue 4 performance)
  size_t lost = 0, reloc = 0, prior = 0;
  const std::clock_t cpu0 = std::clock();  // process CPU time, all threads
  const auto t0 = std::chrono::steady_clock::now();
  for (const auto& f : frames) {
    const TrackResult r = tracker.track(f);
    if (verbose)
      std::fprintf(stderr, "frame %zu %s kf=%d ref=%d matches=%d inliers=%d prior=%d icp_rmse=%.4f overlap=%.3f ms=%.1f (repair %.1f feat %.1f ransac %.1f icp %.1f kf %.1f)\n",
                   f.index, to_string(r.status), int(r.is_keyframe), r.reference_keyframe, r.feature_matches,
                   r.ransac_inliers, int(r.used_motion_prior), r.icp_rmse, r.icp_overlap, r.timings.total_ms,
                   r.timings.repair_ms, r.timings.features_ms, r.timings.ransac_ms, r.timings.icp_ms, r.timings.keyframe_ms);
    ms.push_back(r.timings.total_ms);
    sum.repair_ms += r.timings.repair_ms;
    sum.features_ms += r.timings.features_ms;
    sum.ransac_ms += r.timings.ransac_ms;
    sum.icp_ms += r.timings.icp_ms;
    sum.keyframe_ms += r.timings.keyframe_ms;
    sum.total_ms += r.timings.total_ms;
    lost += r.status == TrackingStatus::lost;
    reloc += r.status == TrackingStatus::relocalised;
    prior += r.used_motion_prior;
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double cpu_ms = 1000.0 * double(std::clock() - cpu0) / CLOCKS_PER_SEC;
  const Trajectory odometry_view = tracker.trajectory();  // before the final optimisation
  const Trajectory traj = tracker.finish();
  const TrackerStats s = tracker.stats();
  json j = evaluate(gt, traj);
  j["ate_before_final_optimisation_m"] = compute_ate(gt, odometry_view).rmse;
  j["median_frame_ms"] = median(ms);
  j["fps_median"] = 1000.0 / std::max(1e-9, median(ms));
  j["fps_wall"] = frames.size() / wall;
  j["max_frame_ms"] = *std::max_element(ms.begin(), ms.end());
  const double nf = double(std::max<size_t>(1, frames.size()));
  j["mean_ms"] = {{"total", sum.total_ms / nf}, {"repair", sum.repair_ms / nf}, {"features", sum.features_ms / nf},
                  {"ransac", sum.ransac_ms / nf}, {"icp", sum.icp_ms / nf}, {"keyframe", sum.keyframe_ms / nf}};
  j["cpu_ms_per_frame"] = cpu_ms / nf;  // includes the loop-closure worker's share
  j["keyframes"] = s.keyframes;
  j["keyframe_reuses"] = s.keyframe_reuses;
  j["loop_edges"] = s.loop_edges;
  j["local_edges"] = s.local_edges;
  j["optimisations"] = s.optimisations;
  j["lost_frames"] = lost;
  j["relocalised_frames"] = reloc;
  j["motion_prior_frames"] = prior;
  // Issue 42: how often each verification check failed on the registration to the reference.
  j["checks"] = {{"verified", s.verified_registrations}, {"dense_residual_failed", s.dense_residual_failed},
                 {"spread_failed", s.spread_failed}, {"ambiguous", s.ambiguous_matches},
                 {"under_constrained", s.under_constrained}};
  if (out_traj) *out_traj = traj;
  return j;
}

#ifdef SEMAP_HAVE_OPEN3D
json run_open3d(const std::vector<Frame>& frames, const CameraModel& camera, const Trajectory& gt) {
  const baseline::Open3dOdometryRun run = baseline::run_open3d_odometry(frames, camera);
  json j = evaluate(gt, run.trajectory);
  j["median_frame_ms"] = median(run.frame_ms);
  j["fps_median"] = 1000.0 / std::max(1e-9, median(run.frame_ms));
  j["failures"] = run.failures;
  return j;
}
#endif

#ifdef SEMAP_HAVE_OPENCV_RGBD
json run_opencv(const std::vector<Frame>& frames, const CameraModel& camera, const Trajectory& gt) {
  const baseline::OpencvOdometryRun run = baseline::run_opencv_odometry(frames, camera);
  json j = evaluate(gt, run.trajectory);
  j["median_frame_ms"] = median(run.frame_ms);
  j["failures"] = run.failures;
  return j;
}
#endif

std::vector<size_t> parse_steps(const std::string& text) {
  std::vector<size_t> steps;
  size_t pos = 0;
  while (pos < text.size()) {
    const size_t comma = text.find(',', pos);
    steps.push_back(std::stoul(text.substr(pos, comma - pos)));
    if (comma == std::string::npos) break;
    pos = comma + 1;
  }
  return steps;
}

/// One "ATE cm / RPE cm/s / RPE deg/s / lost / ms" cell of the k-table.
std::string cell(const json& j, const char* lost_key) {
  char buf[96];
  std::snprintf(buf, sizeof(buf), "%6.2f %6.2f %6.2f %4zu %6.1f", 100 * j["ate_rmse_m"].get<double>(),
                100 * j["rpe_trans_rmse_m_per_s"].get<double>(), j["rpe_rot_rmse_deg_per_s"].get<double>(),
                j.value(lost_key, size_t(0)), j["median_frame_ms"].get<double>());
  return buf;
}

/// Issue 16: the k-table (every k-th frame of both shared sequences, ours beside the baselines).
/// "dense/spread/ambiguous/under-constrained of verified" firing counts of a run (issue 42).
std::string check_counts(const json& ours) {
  const json& c = ours["checks"];
  char buf[96];
  std::snprintf(buf, sizeof(buf), "%zu/%zu/%zu/%zu of %zu", c["dense_residual_failed"].get<size_t>(),
                c["spread_failed"].get<size_t>(), c["ambiguous"].get<size_t>(), c["under_constrained"].get<size_t>(),
                c["verified"].get<size_t>());
  return buf;
}

int run_k_table(const std::vector<size_t>& steps, const TrackingConfig& config, bool baselines, bool keyframe_rate,
                bool compare_verify) {
  namespace fs = std::filesystem;
  const fs::path tmp = fs::temp_directory_path() / ("semap_bench_slices_" + std::to_string(::getpid()));
  json report = json::array();
  std::fprintf(stderr, "%-20s %3s %6s | %-33s | %-33s | %-33s\n", "sequence", "k", "frames",
               "ours: ATE cm RPE cm/s deg/s lost ms", "Open3D hybrid", "OpenCV RgbdICP");
  for (const std::string name : {"tum_fr1_rpy", "7scenes_redkitchen"}) {
    const fs::path source = fs::path(SEMAP_SHARED_DIR) / "data" / name;
    if (!fs::exists(source)) {
      std::fprintf(stderr, "%s: missing, skipped\n", source.c_str());
      continue;
    }
    std::vector<std::pair<std::string, test::SliceSpec>> slices;
    for (size_t k : steps) {
      test::SliceSpec spec;
      spec.step = k;
      slices.emplace_back(std::to_string(k), spec);
    }
    if (keyframe_rate) {
      test::SliceSpec spec;
      spec.frames = test::frames_by_motion(source, 0.25, 20.0);
      slices.emplace_back("kf", spec);
    }
    for (const auto& [k, spec] : slices) {
      const test::SequenceSlice slice = test::write_sequence_slice(source, spec, tmp / (name + k));
      auto reader = open_dataset(slice.dir);
      std::vector<Frame> frames;
      for (size_t i = 0; i < reader->size(); ++i) frames.push_back(reader->load(i));
      const Trajectory gt = reader->ground_truth();
      json row = {{"sequence", name}, {"k", k}, {"frames", frames.size()}};
      if (k == "kf") row["source_frames"] = slice.source_index;
      row["ours"] = run_ours(frames, reader->camera(), config, gt, nullptr);
      if (compare_verify) {  // issue 42: the same frames with the registration checks off (before)
        TrackingConfig unverified = config;
        unverified.verify.enabled = false;
        row["ours_unverified"] = run_ours(frames, reader->camera(), unverified, gt, nullptr);
      }
      std::string o3 = "n/a", ocv = "n/a";
#ifdef SEMAP_HAVE_OPEN3D
      if (baselines) {
        row["open3d_hybrid"] = run_open3d(frames, reader->camera(), gt);
        o3 = cell(row["open3d_hybrid"], "failures");
      }
#endif
#ifdef SEMAP_HAVE_OPENCV_RGBD
      if (baselines) {
        row["opencv_rgbd_icp"] = run_opencv(frames, reader->camera(), gt);
        ocv = cell(row["opencv_rgbd_icp"], "failures");
      }
#endif
      std::fprintf(stderr, "%-20s %3s %6zu | %s | %s | %s | checks d/s/a/u %s\n", name.c_str(), k.c_str(), frames.size(),
                   cell(row["ours"], "lost_frames").c_str(), o3.c_str(), ocv.c_str(), check_counts(row["ours"]).c_str());
      if (compare_verify)
        std::fprintf(stderr, "%-20s %3s %6zu | %s | (checks off; CPU ms/frame %.1f on, %.1f off)\n", "  unverified", k.c_str(),
                     frames.size(), cell(row["ours_unverified"], "lost_frames").c_str(),
                     row["ours"]["cpu_ms_per_frame"].get<double>(), row["ours_unverified"]["cpu_ms_per_frame"].get<double>());
      report.push_back(row);
      fs::remove_all(tmp / (name + k));
    }
  }
  std::error_code ec;
  fs::remove_all(tmp, ec);
  std::cout << report.dump(2) << std::endl;
  return 0;
}
}  // namespace

int main(int argc, char** argv) {
  try {
    std::string dataset = std::string(SEMAP_SHARED_DIR) + "/data/tum_fr1_rpy";
    size_t max_frames = 0;
    bool open3d = true, repair_compare = true, loop_compare = true, deterministic = false, k_table = false;
    bool keyframe_rate = true, compare_verify = false;
    std::vector<size_t> steps = {1, 3, 5, 10};
    std::string out_trajectory;
    std::vector<std::string> overrides;
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--frames" && i + 1 < argc) max_frames = std::stoul(argv[++i]);
      else if (a == "--no-open3d") open3d = false;
      else if (a == "--no-repair-compare") repair_compare = false;
      else if (a == "--no-loop-compare") loop_compare = false;
      else if (a == "--deterministic") deterministic = true;
      else if (a == "--k-table") k_table = true;
      else if (a == "--steps" && i + 1 < argc) steps = std::string(argv[i + 1]) == "none" ? (++i, std::vector<size_t>{}) : parse_steps(argv[++i]);
      else if (a == "--no-keyframe-rate") keyframe_rate = false;
      else if (a == "--compare-verify") compare_verify = true;
      else if (a == "--verbose") verbose = true;
      else if (a == "--threads" && i + 1 < argc) cv::setNumThreads(std::stoi(argv[++i]));  // OpenCV/TBB workers
      else if (a == "--out-trajectory" && i + 1 < argc) out_trajectory = argv[++i];
      else if (a == "--set" && i + 1 < argc) overrides.push_back(argv[++i]);
      else if (!a.empty() && a[0] != '-') dataset = a;
      else throw Error(a, "unknown argument");
    }
    if (k_table) {
      TrackingConfig config;
      config.background_loop_closure = !deterministic;
      for (const auto& o : overrides) load_config_string(o, "--set", [&](ParamVisitor& v) { config.visit(v); });
      config.validate();
      return run_k_table(steps, config, open3d, keyframe_rate, compare_verify);
    }
    auto reader = open_dataset(dataset);
    const size_t n = max_frames ? std::min(max_frames, reader->size()) : reader->size();
    std::vector<Frame> frames;
    frames.reserve(n);
    for (size_t i = 0; i < n; ++i) frames.push_back(reader->load(i));
    Trajectory gt;
    for (const auto& f : frames)
      if (f.gt_T_world_camera) gt.push_back({f.timestamp, *f.gt_T_world_camera});
    if (gt.size() < 3) gt = reader->ground_truth();

    json report;
    report["dataset"] = dataset;
    report["frames"] = n;
    report["threads_hint"] = "run under the project's 2-core budget";
    TrackingConfig config;
    config.background_loop_closure = !deterministic;
    for (const auto& o : overrides) load_config_string(o, "--set", [&](ParamVisitor& v) { config.visit(v); });
    config.validate();
    Trajectory traj;
    report["ours"] = run_ours(frames, reader->camera(), config, gt, &traj);
    if (!out_trajectory.empty()) write_tum_trajectory(out_trajectory, traj);
    if (repair_compare) {
      TrackingConfig no_repair = config;
      no_repair.depth_repair.enabled = false;
      report["ours_without_depth_repair"] = run_ours(frames, reader->camera(), no_repair, gt, nullptr);
    }
    if (loop_compare) {
      TrackingConfig odometry_only = config;
      odometry_only.pose_graph = false;
      odometry_only.keyframe_reuse = false;
      report["ours_odometry_only"] = run_ours(frames, reader->camera(), odometry_only, gt, nullptr);
    }
#ifdef SEMAP_HAVE_OPEN3D
    if (open3d) {
      report["open3d_hybrid_frame_to_frame"] = run_open3d(frames, reader->camera(), gt);
      report["ours_ate_lower_than_open3d"] =
          report["ours"]["ate_rmse_m"].get<double>() < report["open3d_hybrid_frame_to_frame"]["ate_rmse_m"].get<double>();
    }
#else
    (void)open3d;
    report["open3d_hybrid_frame_to_frame"] = "Open3D not found at build time";
#endif
    std::cout << report.dump(2) << std::endl;
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_tracking: %s\n", e.what());
    return 1;
  }
}
