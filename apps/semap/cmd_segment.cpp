// semap segment IMAGE... --model M [--config C] --out DIR  (issue 5 CLI)
#include <spdlog/spdlog.h>

#include <chrono>
#include <map>
#include <memory>

#include "apps/semap/commands.hpp"
#include "semap/core/error.hpp"
#include "core/paths.hpp"
#include "io/image_io.hpp"
#include "io/output_folder.hpp"
#include "semap/pipeline/semap_config.hpp"
#include "segmentation/segmentation_io.hpp"
#include "semap/segmentation/segmenter_factory.hpp"

namespace semap::app {

namespace {
struct SegmentOptions {
  std::vector<std::string> images;
  std::string model, config, out;
};
}  // namespace

void add_segment_command(CLI::App& app, CommandRunner& run) {
  auto opts = std::make_shared<SegmentOptions>();
  auto* cmd = app.add_subcommand(
      "segment",
      "Segment RGB images with an ONNX model; writes NAME.label.png (16-bit project class ids), "
      "NAME.instances.png (16-bit, 0 = none), NAME.json and NAME.overlay.png per image");
  cmd->add_option("images", opts->images, "RGB images")->required();
  cmd->add_option("--model,-m", opts->model,
                  "yolo:PATH, semantic:PATH, precomputed:DIR or PATH.onnx (kind detected from the graph)")
      ->required();
  cmd->add_option("--config,-c", opts->config, "YAML config (the segmentation section is used)");
  cmd->add_option("--out,-o", opts->out, "output folder")->required();
  cmd->callback([&run, opts] {
    run = [opts]() -> int {
      const InterruptGuard interrupts;  // Ctrl-C: stop between images, publish nothing
      const SemapConfig config = load_semap_config(opts->config);
      // Outputs are named after the image: two inputs with one name would overwrite each other.
      std::map<std::string, std::string> by_name;
      for (const auto& image : opts->images) {
        const std::string name = std::filesystem::path(image).stem().string();
        if (name.empty()) throw Error(image, "has no file name to name its outputs after");
        if (const auto [it, added] = by_name.emplace(name, image); !added)
          throw Error(image, "has the same name '" + name + "' as " + it->second +
                                 ": their outputs would overwrite each other (segment them into separate --out folders)");
        require_regular_file(image, "image");
      }
      auto segmenter = make_segmenter(opts->model, config.segmentation, CameraModel{});
      if (!segmenter) throw Error("--model", "'" + opts->model + "' gives no segmenter");
      // Staged and published at the end (io/output_folder.hpp); earlier calls' outputs stay.
      // Never into the images' folder, the model or the precomputed folder read (issue 44).
      std::vector<std::filesystem::path> inputs(opts->images.begin(), opts->images.end());
      for (const auto& path : segmenter_input_paths(opts->model)) inputs.push_back(path);
      if (!opts->config.empty()) inputs.emplace_back(opts->config);
      OutputFolder out(opts->out, {.tool = "segment", .refuse_foreign_non_empty = false, .remove_stale = false, .publish_last = {},
                                   .inputs = inputs});
      for (size_t i = 0; i < opts->images.size(); ++i) {
        throw_if_interrupted();
        const std::filesystem::path path = opts->images[i];
        Frame frame;
        frame.index = i;
        frame.rgb = read_colour_image(path);
        frame.rgb_path = path.string();
        const auto t0 = std::chrono::steady_clock::now();
        const SegmentationResult result = segmenter->segment(frame);
        const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        const std::string name = path.stem().string();
        write_segmentation(out.staging(), name, frame.rgb, result, segmenter->name());
        std::string summary;
        for (const auto& inst : result.instances)
          summary += fmt::format(" {} {:.2f}", class_name(inst.class_id), inst.score);
        spdlog::info("{}: {} instances in {:.0f} ms{}", path.string(), result.instances.size(), ms, summary);
      }
      throw_if_interrupted();
      out.publish();
      return 0;
    };
  });
}

}  // namespace semap::app
