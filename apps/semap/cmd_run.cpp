#include <chrono>
#include <cstdio>
#include <thread>

#include "apps/semap/commands.hpp"
#include "apps/semap/live_view.hpp"
#include "io/output_folder.hpp"
#include "pipeline/report.hpp"
#include "semap/pipeline/run_pipeline.hpp"

namespace semap::app {

namespace {

// The outputs are already published: Ctrl-C here only ends the wait.
void keep_serving_final_map(double seconds) {
  if (seconds <= 0 || interrupt_signal() != 0) return;
  std::printf("semap run: serving the final map for %.0f s more (Ctrl-C to stop)\n", seconds);
  std::fflush(stdout);
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (interrupt_signal() == 0 && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
}

}  // namespace

void add_run_command(CLI::App& app, CommandRunner& run) {
  auto* cmd = app.add_subcommand("run", "Map a dataset: trajectory, semantic TSDF mesh, object map");
  struct Args {
    RunOptions options;
    std::string config_path;
    double voxel = 0;
    int threads = 0;
    int64_t max_frames = 0;
    bool view = false;
    int view_port = 8765;
    int view_refresh_ms = 1500;
    double view_keep_s = 0;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("dataset", args->options.dataset,
                  "dataset folder or file (TUM, 7-Scenes, YCB-Video, ScanNet, synthetic, dataset.yaml, ROS .bag, rosbag2 folder / .db3 / .mcap) or a "
                  "camera (openni2:, openni2:URI, openni2:FILE.oni)")
      ->required();
  cmd->add_option("--rgb-topic", args->options.dataset_options.rgb_topic, "ROS bag / rosbag2: the colour image topic (default: the only one)");
  cmd->add_option("--depth-topic", args->options.dataset_options.depth_topic, "ROS bag / rosbag2: the depth image topic (default: the only one)");
  cmd->add_option("--out", args->options.out_dir, "output folder")->required();
  cmd->add_option("--config", args->config_path, "YAML config (see `semap config --dump`)");
  cmd->add_option("--resume", args->options.resume_from,
                  "continue the map of an earlier run (its output folder or map.semap): relocalise into it and extend it");
  add_enum_option(cmd, "--poses", args->options.poses, kRunPoseSourceNames, "camera poses");
  cmd->add_option("--segmenter", args->options.segmenter,
                  "yolo:MODEL | semantic:MODEL | panoptic:SEMANTIC.onnx+INSTANCE.onnx | groundtruth | precomputed:DIR | "
                  "none (geometry and colour only) | default (the default: the config's segmentation.segmenter, "
                  "whose default is the default models when found)");
  cmd->add_option("--models", args->options.models_dir,
                  "folder of the default segmentation models (else $SEMAP_MODELS_DIR, the install's "
                  "share/semap/models, a source build's ../shared/models)");
  cmd->add_option("--seg-noise", args->options.seg_noise, "simulate an imperfect segmenter on ground-truth labels (flicker rate 0..1)")
      ->check(finite_in(0.0, 1.0));
  cmd->add_option("--voxel", args->voxel, "TSDF voxel size in metres (overrides the config)")->check(finite_in(0.001, 1.0));
  cmd->add_option("--max-frames", args->max_frames, "stop after N frames (0 = all)")->check(CLI::Range(int64_t{0}, int64_t{1} << 40));
  cmd->add_option("--threads", args->threads, "worker threads (overrides the config; 1 = deterministic)")->check(CLI::Range(1, 256));
  cmd->add_flag("--realtime", args->options.realtime,
                "feed the frames at their recorded pace (timestamps), as the camera delivered them; none is dropped");
  cmd->add_flag("--no-eval", [args](int64_t) { args->options.evaluate = false; }, "skip evaluation against ground truth");
  cmd->add_flag("--view", args->view, "serve the growing map to the browser viewer on 127.0.0.1 while mapping");
  cmd->add_option("--port", args->view_port, "--view: TCP port (0: any free port)")->check(CLI::Range(0, 65535))->capture_default_str();
  cmd->add_option("--view-refresh-ms", args->view_refresh_ms, "--view: how often the map is refreshed")
      ->check(CLI::Range(200, 60000))->capture_default_str();
  cmd->add_option("--view-keep-s", args->view_keep_s,
                  "--view: after the outputs are written, keep serving the final map this long (Ctrl-C ends it sooner)")
      ->check(finite_in(0.0, 86400.0))->capture_default_str();
  cmd->callback([&run, args] {
    run = [args]() -> int {
      SemapConfig config = load_semap_config(args->config_path);
      if (args->voxel > 0) config.tsdf.voxel_size = args->voxel;
      if (args->voxel > 0 && !args->options.resume_from.empty())  // issue 44: not silently ignored
        std::fprintf(stderr, "semap run: warning: --voxel %g ignored: --resume continues the saved map at its own voxel size\n",
                     args->voxel);
      if (args->threads > 0) config.pipeline.threads = args->threads;
      config.validate();
      args->options.max_frames = static_cast<size_t>(args->max_frames);
      // First Ctrl-C: stop reading, finish the map and publish it; a second one quits and
      // publishes nothing (io/output_folder.hpp).
      const InterruptGuard interrupts;
      args->options.stop_requested = [] { return interrupt_signal() != 0; };
      std::unique_ptr<LiveView> live;
      if (args->view) {
        live = std::make_unique<LiveView>("127.0.0.1", args->view_port, std::chrono::milliseconds(args->view_refresh_ms),
                                          "live: " + args->options.dataset.filename().string());
        args->options.observe_mapper = [&live](const Mapper* mapper) { live->observe(mapper); };
      }
      const RunResult result = run_pipeline(args->options, config);
      if (live)
        std::printf("semap run: live view refreshed %zu times (`semap view %s` shows the final map later)\n",
                    live->snapshots(), args->options.out_dir.string().c_str());
      if (result.stopped_early)
        std::fprintf(stderr, "semap run: interrupted: mapped the %zu frames read so far\n", result.frames_read);
      std::fputs(summary_table(to_json(result)).c_str(), stdout);
      std::printf("outputs in %s\n", args->options.out_dir.string().c_str());
      if (live) keep_serving_final_map(args->view_keep_s);
      return 0;
    };
  });
}

}  // namespace semap::app
