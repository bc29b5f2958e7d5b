// `semap synth`: renders the embedded synthetic dataset (procedural room, perfect ground truth).
#include <cstdio>
#include <memory>

#include "apps/semap/commands.hpp"
#include "semap/core/error.hpp"
#include "semap/io/config_loader.hpp"
#include "io/output_folder.hpp"
#include "synth/synth_config.hpp"

namespace semap::app {

namespace {
struct SynthOptions {
  SynthConfig config;
  std::string out;
  std::string config_file;
  int64_t seed = 1;
};
}  // namespace

void add_synth_command(CLI::App& app, CommandRunner& run) {
  auto* cmd = app.add_subcommand("synth", "Render the synthetic RGB-D dataset with perfect ground truth");
  auto opt = std::make_shared<SynthOptions>();
  cmd->add_option("--out", opt->out,
                  "output folder: new, empty, or made by an earlier `semap synth` (never someone else's data); "
                  "published only when complete")
      ->required();
  cmd->add_option("--config", opt->config_file, "YAML with a 'synth' section (applied before the flags)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--frames", opt->config.frames, "number of frames (one closed loop)")->capture_default_str();
  cmd->add_option("--seed", opt->seed, "random seed (scene, textures, noise)")->capture_default_str();
  cmd->add_option("--objects", opt->config.objects, "number of object instances")->capture_default_str();
  cmd->add_flag("--depth-noise", opt->config.depth_noise, "Kinect-like depth noise");
  cmd->add_option("--seg-noise", opt->config.seg_noise,
                  "also write label_noisy/ instance_noisy/ with this per-frame flicker rate")
      ->capture_default_str();
  cmd->add_option("--width", opt->config.width, "image width")->capture_default_str();
  cmd->add_option("--height", opt->config.height, "image height")->capture_default_str();
  cmd->callback([&run, opt, cmd] {
    run = [opt, cmd]() -> int {
      const InterruptGuard interrupts;  // Ctrl-C: stop between frames, publish nothing
      SynthConfig config;
      if (!opt->config_file.empty())
        load_config_file(opt->config_file, [&](ParamVisitor& v) {
          v.section("synth", "synthetic dataset", [&](ParamVisitor& s) { config.visit(s); });
        });
      // Flags given on the command line win over the file.
      if (opt->config_file.empty() || cmd->count("--frames")) config.frames = opt->config.frames;
      if (opt->config_file.empty() || cmd->count("--objects")) config.objects = opt->config.objects;
      if (opt->config_file.empty() || cmd->count("--depth-noise")) config.depth_noise = opt->config.depth_noise;
      if (opt->config_file.empty() || cmd->count("--seg-noise")) config.seg_noise = opt->config.seg_noise;
      if (opt->config_file.empty() || cmd->count("--width")) config.width = opt->config.width;
      if (opt->config_file.empty() || cmd->count("--height")) config.height = opt->config.height;
      if (opt->config_file.empty() || cmd->count("--seed")) {
        if (opt->seed < 0) throw Error("--seed", "must be >= 0");
        config.seed = static_cast<uint64_t>(opt->seed);
      }
      const SynthStats stats = generate_dataset(config, opt->out);
      std::printf("semap synth: %d frames, %zu objects, %zu gt points -> %s\n", config.frames, stats.objects,
                  stats.gt_points, opt->out.c_str());
      std::printf("renderer: %.1f frames/s at %dx%d (ray casting only, wall clock; %.1f ms CPU per frame); "
                  "%.1f frames/s overall incl. noise + PNG writing\n",
                  stats.render_fps, config.width, config.height, 1000.0 * stats.render_cpu_s_per_frame, stats.total_fps);
      return 0;
    };
  });
}

}  // namespace semap::app
