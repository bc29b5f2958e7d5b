#include <chrono>
#include <cstdio>

#include "apps/semap/commands.hpp"
#include "io/output_folder.hpp"
#include "semap/pipeline/run_pipeline.hpp"
#include "pipeline/report.hpp"
#include "synth/synth_config.hpp"

namespace semap::app {

void add_demo_command(CLI::App& app, CommandRunner& run) {
  auto* cmd = app.add_subcommand(
      "demo", "Generate the synthetic world, map it end to end (tracking, noisy segmentation, TSDF, objects) and evaluate");
  struct Args {
    std::filesystem::path out = "demo_out";
    int frames = 240;
    uint64_t seed = 1;
    double seg_noise = 0.2;
    std::string config_path;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("--out", args->out, "output folder (the dataset goes to OUT/dataset)");
  cmd->add_option("--frames", args->frames, "frames of the synthetic loop")->check(CLI::Range(10, 100000));
  cmd->add_option("--seed", args->seed, "scene seed");
  cmd->add_option("--seg-noise", args->seg_noise, "label flicker rate of the built-in noisy segmenter")->check(finite_in(0.0, 1.0));
  cmd->add_option("--config", args->config_path, "YAML config (see `semap config --dump`)");
  cmd->callback([&run, args] {
    run = [args]() -> int {
      const auto t0 = std::chrono::steady_clock::now();
      const InterruptGuard interrupts;  // Ctrl-C: see `semap run`
      SemapConfig config = load_semap_config(args->config_path);
      SynthConfig synth;
      synth.frames = args->frames;
      synth.seed = args->seed;
      synth.depth_noise = true;
      const std::filesystem::path dataset = args->out / "dataset";
      std::printf("semap demo: generating the synthetic world (%d frames, seed %llu) in %s\n", synth.frames,
                  static_cast<unsigned long long>(synth.seed), dataset.string().c_str());
      const SynthStats stats = generate_dataset(synth, dataset);
      std::printf("semap demo: rendered at %.1f frames/s; mapping with tracking and noisy segmentation (flicker %.0f %%)\n",
                  stats.render_fps, args->seg_noise * 100);
      RunOptions options;
      options.dataset = dataset;
      options.out_dir = args->out;
      options.dataset_inside_out_dir = true;  // OUT/dataset: generated just above
      options.poses = PoseSource::track;
      options.segmenter = "groundtruth";
      options.seg_noise = args->seg_noise;
      options.stop_requested = [] { return interrupt_signal() != 0; };
      const RunResult result = run_pipeline(options, config);
      std::fputs(summary_table(to_json(result)).c_str(), stdout);
      const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::printf("semap demo: done in %.1f s. Open %s/report.html, or `semap view %s`.\n", wall,
                  args->out.string().c_str(), args->out.string().c_str());
      return 0;
    };
  });
}

}  // namespace semap::app
