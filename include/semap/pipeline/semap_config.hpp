#pragma once
// The root of the one YAML config: one section per stage. `semap config --dump` prints it.
#include <filesystem>
#include <string>

#include "semap/core/params.hpp"
#include "semap/objects/objects_config.hpp"
#include "semap/segmentation/segmentation_config.hpp"
#include "semap/synth/segmentation_noise.hpp"
#include "semap/tracking/tracking_config.hpp"
#include "semap/tsdf/tsdf_config.hpp"

namespace semap {

struct PipelineConfig {
  int threads = 2;        ///< worker threads for the parallel stages (1 = deterministic)
  int queue_size = 8;     ///< bounded queue length between stages, frames
  int refresh_cache_mb = 256;  ///< memory for the repair fills the final map refresh reuses

  void visit(ParamVisitor& v) {
    v.param("threads", threads, "", "worker threads (1 gives byte-identical outputs)");
    v.param("queue_size", queue_size, "frames", "bounded queue length between stages");
    v.param("refresh_cache_mb", refresh_cache_mb, "MiB",
            "memory for the depth-repair fills the final map refresh reuses instead of decoding colour and "
            "repairing again (frames past it are re-read; 0 = re-read every frame)");
  }
  void validate() const {
    require_param(threads >= 1 && threads <= 256, "pipeline.threads", "must be in [1, 256]");
    require_param(queue_size >= 1, "pipeline.queue_size", "must be >= 1");
    require_param(refresh_cache_mb >= 0 && refresh_cache_mb <= (1 << 20), "pipeline.refresh_cache_mb",
                  "must be in [0, 1048576]");
  }
};

struct SemapConfig {
  PipelineConfig pipeline;
  TrackingConfig tracking;
  SegmentationConfig segmentation;
  TsdfConfig tsdf;
  ObjectsConfig objects;
  /// The built-in noisy segmenter (`--seg-noise`, `semap demo`); flicker_rate is set by the CLI.
  SegmentationNoiseParams simulated_segmentation;

  void visit(ParamVisitor& v) {
    v.section("pipeline", "threads and queues", [&](ParamVisitor& s) { pipeline.visit(s); });
    v.section("tracking", "camera tracking (METHODS A1-A4)", [&](ParamVisitor& s) { tracking.visit(s); });
    v.section("segmentation", "segmentation (METHODS C1, B1, B2)", [&](ParamVisitor& s) { segmentation.visit(s); });
    v.section("tsdf", "dense semantic TSDF (METHODS B3-B7, A6)", [&](ParamVisitor& s) { tsdf.visit(s); });
    v.section("objects", "object map (METHODS C2-C5)", [&](ParamVisitor& s) { objects.visit(s); });
    v.section("simulated_segmentation", "built-in noisy segmenter on ground-truth labels (--seg-noise, demo)",
              [&](ParamVisitor& s) { simulated_segmentation.visit(s); });
  }
  void validate() const {
    pipeline.validate();
    tracking.validate();
    segmentation.validate();
    tsdf.validate();
    objects.validate();
    simulated_segmentation.validate();
  }
};

/// Defaults overridden by the YAML file (if not empty); validated. Throws semap::Error.
SemapConfig load_semap_config(const std::filesystem::path& yaml_path);
/// YAML text of the defaults with docs.
std::string dump_default_config();

}  // namespace semap
