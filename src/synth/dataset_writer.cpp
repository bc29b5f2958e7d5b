// generate_dataset(): the synthetic dataset of notes/SHARED_FORMATS.md, written into a staging
// folder inside the target and published at the very end (io/output_folder.hpp).
#include <fmt/format.h>
#include <tbb/parallel_invoke.h>
#include <unistd.h>

#include <chrono>
#include <ctime>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "semap/core/error.hpp"
#include "core/paths.hpp"
#include "core/progress.hpp"
#include "io/image_io.hpp"
#include "io/output_folder.hpp"
#include "semap/io/ply_io.hpp"
#include "semap/io/trajectory_io.hpp"
#include "synth/depth_noise.hpp"
#include "synth/gt_points.hpp"
#include "synth/random.hpp"
#include "synth/renderer.hpp"
#include "synth/scene.hpp"
#include "semap/synth/segmentation_noise.hpp"
#include "synth/synth_config.hpp"
#include "synth/trajectory.hpp"

namespace semap {
namespace fs = std::filesystem;
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

nlohmann::json obb_json(const Obb& o) {
  nlohmann::json j;
  j["center"] = {o.center.x(), o.center.y(), o.center.z()};
  j["extent"] = {o.extent.x(), o.extent.y(), o.extent.z()};
  std::vector<double> r;
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) r.push_back(o.rotation(i, k));
  j["rotation"] = r;
  return j;
}

const char* shape_name(PrimitiveShape s) {
  switch (s) {
    case PrimitiveShape::kBox: return "box";
    case PrimitiveShape::kCylinder: return "cylinder";
    default: return "sphere";
  }
}

std::string scene_json(const SyntheticScene& scene, const SynthConfig& cfg) {
  nlohmann::json j;
  j["room"] = {{"min", {0.0, 0.0, 0.0}},
               {"max", {scene.room.size.x(), scene.room.size.y(), scene.room.size.z()}},
               {"size", {scene.room.size.x(), scene.room.size.y(), scene.room.size.z()}},
               {"up", {0.0, 0.0, 1.0}}};
  j["generator"] = {{"seed", cfg.seed},           {"frames", cfg.frames},       {"objects", cfg.objects},
                    {"depth_noise", cfg.depth_noise}, {"seg_noise", cfg.seg_noise}, {"width", cfg.width},
                    {"height", cfg.height}};
  nlohmann::json objects = nlohmann::json::array();
  for (const SceneObject& o : scene.objects) {
    nlohmann::json jo;
    jo["instance_id"] = o.instance_id;
    jo["class"] = std::string(class_name(o.class_id));
    jo["class_id"] = o.class_id;
    jo["obb"] = obb_json(o.obb);
    jo["support"] = o.support;
    nlohmann::json prims = nlohmann::json::array();
    for (uint32_t pi : o.primitives) {
      const Primitive& p = scene.primitives[pi];
      nlohmann::json jp = obb_json(p.bounds());
      jp["shape"] = shape_name(p.shape);
      prims.push_back(jp);
    }
    jo["primitives"] = prims;
    objects.push_back(jo);
  }
  j["objects"] = objects;
  nlohmann::json stuff = nlohmann::json::array();
  for (const Primitive& p : scene.primitives)
    if (p.instance == 0) {
      nlohmann::json js = obb_json(p.bounds());
      js["class"] = std::string(class_name(p.label));
      js["class_id"] = p.label;
      stuff.push_back(js);
    }
  j["stuff"] = stuff;
  return j.dump(2) + "\n";
}

std::string frame_name(int i) { return fmt::format("{:06d}.png", i); }

}  // namespace

SynthStats generate_dataset(const SynthConfig& cfg, const fs::path& out_dir) {
  cfg.validate();
  if (out_dir.empty()) throw Error("synth", "no output folder given");
  // A new or empty folder, or one an earlier `semap synth` made (io/output_folder.hpp): never a
  // folder of someone else's data. Everything is staged inside it and published at the end;
  // files of an earlier, larger dataset there are removed, nothing else is.
  OutputFolder folder(out_dir, {.tool = "synth", .refuse_foreign_non_empty = true, .remove_stale = true,
                                .publish_last = {"dataset.yaml"}, .inputs = {}});
  const fs::path tmp = folder.staging();
  const bool noisy_seg = cfg.seg_noise > 0;
  for (const char* sub : {"rgb", "depth", "label", "instance"}) fs::create_directories(tmp / sub);
  if (noisy_seg)
    for (const char* sub : {"label_noisy", "instance_noisy"}) fs::create_directories(tmp / sub);

  try {
    const SyntheticScene scene =
        make_scene(cfg.seed, cfg.objects, Eigen::Vector3d(cfg.room_x, cfg.room_y, cfg.room_z));
    const PinholeIntrinsics K = synth_intrinsics(cfg.width, cfg.height);
    LoopTrajectoryParams traj_params;
    traj_params.mean_height = cfg.camera_height;
    traj_params.start_time = 1.0;
    Trajectory traj = make_loop_trajectory(scene.room.size, cfg.frames, cfg.fps, traj_params);
    // Timestamps exactly representable with 6 decimals, so every list agrees with groundtruth.txt.
    for (StampedPose& p : traj) p.timestamp = std::round(p.timestamp * 1e6) / 1e6;

    const PointCloud samples = sample_scene_surface(scene, cfg.gt_point_spacing);
    std::vector<uint8_t> observed(samples.size(), 0);
    SegmentationNoiseParams seg_params = cfg.seg_noise_params;
    seg_params.flicker_rate = cfg.seg_noise;

    std::string rgb_list = "# synthetic rgb (semap synth)\n# timestamp filename\n";
    std::string depth_list = "# synthetic depth, 16-bit PNG, 5000 per metre\n# timestamp filename\n";
    std::string label_list = "# synthetic semantic labels, 8-bit project class ids\n# timestamp filename\n";
    std::string instance_list = "# synthetic instance ids, 16-bit, 0 = stuff/none\n# timestamp filename\n";
    std::string label_noisy_list = "# noisy semantic labels\n# timestamp filename\n";
    std::string instance_noisy_list = "# noisy instance ids\n# timestamp filename\n";

    Progress progress("synth", static_cast<size_t>(cfg.frames));
    double render_s = 0, render_cpu_s = 0;
    const auto start = Clock::now();
    for (int i = 0; i < cfg.frames; ++i) {
      throw_if_interrupted();
      const Pose& pose = traj[i].T_world_camera;
      const auto t0 = Clock::now();
      const std::clock_t c0 = std::clock();
      const RenderedFrame frame = render(scene, pose, K);
      render_s += seconds_since(t0);
      render_cpu_s += static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
      mark_observed_points(samples, frame.depth, pose, K, cfg.gt_visibility_tolerance, observed);
      const uint64_t frame_seed = synth_detail::hash_combine(cfg.seed, static_cast<uint64_t>(i));
      const std::string name = frame_name(i);
      cv::Mat depth = cfg.depth_noise
                          ? apply_depth_noise(frame.depth, frame.cos_incidence, K.fx, frame_seed ^ 0xde97ULL,
                                              cfg.depth_noise_params)
                          : frame.depth;
      tbb::parallel_invoke([&] { write_image(tmp / "rgb" / name, frame.rgb); },
                           [&] { write_depth_image(tmp / "depth" / name, depth, 5000.0); },
                           [&] { write_image(tmp / "label" / name, frame.labels); },
                           [&] { write_image(tmp / "instance" / name, frame.instances); },
                           [&] {
                             if (!noisy_seg) return;
                             const auto [labels, instances] =
                                 apply_segmentation_noise(frame.labels, frame.instances, frame_seed ^ 0x5e9ULL, seg_params);
                             write_image(tmp / "label_noisy" / name, labels);
                             write_image(tmp / "instance_noisy" / name, instances);
                           });
      const std::string stamp = fmt::format("{:.6f}", traj[i].timestamp);
      rgb_list += stamp + " rgb/" + name + "\n";
      depth_list += stamp + " depth/" + name + "\n";
      label_list += stamp + " label/" + name + "\n";
      instance_list += stamp + " instance/" + name + "\n";
      label_noisy_list += stamp + " label_noisy/" + name + "\n";
      instance_noisy_list += stamp + " instance_noisy/" + name + "\n";
      progress.update(static_cast<size_t>(i + 1), fmt::format("render {:.1f} fps", (i + 1) / std::max(render_s, 1e-9)));
    }
    const double loop_s = seconds_since(start);

    write_file_atomic(tmp / "rgb.txt", rgb_list);
    write_file_atomic(tmp / "depth.txt", depth_list);
    write_file_atomic(tmp / "label.txt", label_list);
    write_file_atomic(tmp / "instance.txt", instance_list);
    if (noisy_seg) {
      write_file_atomic(tmp / "label_noisy.txt", label_noisy_list);
      write_file_atomic(tmp / "instance_noisy.txt", instance_noisy_list);
    }
    write_tum_trajectory(tmp / "groundtruth.txt", traj);
    write_file_atomic(tmp / "scene.json", scene_json(scene, cfg));
    const PointCloud kept = select_points(samples, observed);
    write_ply(tmp / "gt_points.ply", kept);
    // dataset.yaml is published last: its presence marks a complete dataset.
    write_file_atomic(tmp / "dataset.yaml",
                      fmt::format("format: synthetic\ncamera: {{fx: {}, fy: {}, cx: {}, cy: {}, width: {}, height: {}, "
                                  "depth_scale: 5000}}\n",
                                  K.fx, K.fy, K.cx, K.cy, K.width, K.height));
    throw_if_interrupted();
    folder.publish();

    SynthStats stats;
    stats.render_fps = cfg.frames / std::max(render_s, 1e-9);
    stats.render_cpu_s_per_frame = render_cpu_s / cfg.frames;
    stats.total_fps = cfg.frames / std::max(loop_s, 1e-9);
    stats.gt_points = kept.size();
    stats.objects = scene.objects.size();
    progress.finish(fmt::format("render {:.1f} fps", stats.render_fps));
    return stats;
  } catch (const fs::filesystem_error& e) {
    throw Error(e.path1().empty() ? out_dir : e.path1(), e.code().message());
  }
}

}  // namespace semap
