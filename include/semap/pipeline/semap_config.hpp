#pragma once
// The root of the one YAML config: one section per stage. `semap config --dump` prints it.
#include <filesystem>
#include <string>

#include "semap/core/params.hpp"
#include "semap/navigation/navigation_config.hpp"
#include "semap/objects/objects_config.hpp"
#include "semap/segmentation/segmentation_config.hpp"
#include "semap/synth/segmentation_noise.hpp"
#include "semap/tracking/tracking_config.hpp"
#include "semap/tsdf/tsdf_config.hpp"

namespace semap {

struct PipelineConfig {
  int threads = 2;
  int queue_size = 8;
  int refresh_cache_mb = 256;

  void visit(ParamVisitor& v) {
    v.param("threads", threads, "", "worker threads (1: every stage inline, byte-identical outputs)", {1, 256});
    v.param("queue_size", queue_size, "frames", "bounded queue length between stages", {1, 1024});
    v.param("refresh_cache_mb", refresh_cache_mb, "MiB",
            "memory the final map refresh keeps: the depth-repair fills of frames it can re-read, or compressed "
            "copies of the frames when nothing can re-read them (a camera, a library caller); 0 = keep nothing",
            {0, 1 << 20});
  }
  void validate() const { check_param_ranges(*this, "pipeline"); }
};

struct SemapConfig {
  PipelineConfig pipeline;
  TrackingConfig tracking;
  SegmentationConfig segmentation;
  TsdfConfig tsdf;
  ObjectsConfig objects;
  /// The built-in noisy segmenter (`--seg-noise`, `semap demo`); flicker_rate is set by the CLI.
  SegmentationNoiseParams simulated_segmentation;
  NavigationConfig navigation;  ///< issue 39: occupancy grid, distance field, scene graph

  void visit(ParamVisitor& v) {
    v.section("pipeline", "threads and queues", [&](ParamVisitor& s) { pipeline.visit(s); });
    v.section("tracking", "camera tracking (METHODS A1-A4)", [&](ParamVisitor& s) { tracking.visit(s); });
    v.section("segmentation", "segmentation (METHODS C1, B1, B2)", [&](ParamVisitor& s) { segmentation.visit(s); });
    v.section("tsdf", "dense semantic TSDF (METHODS B3-B7, A6)", [&](ParamVisitor& s) { tsdf.visit(s); });
    v.section("objects", "object map (METHODS C2-C5)", [&](ParamVisitor& s) { objects.visit(s); });
    v.section("simulated_segmentation", "built-in noisy segmenter on ground-truth labels (--seg-noise, demo)",
              [&](ParamVisitor& s) { simulated_segmentation.visit(s); });
    v.section("navigation", "occupancy grid, distance field and scene graph (issue 39)",
              [&](ParamVisitor& s) { navigation.visit(s); });
  }
  void validate() const {
    pipeline.validate();
    tracking.validate();
    segmentation.validate();
    tsdf.validate();
    objects.validate();
    simulated_segmentation.validate();
    navigation.validate();
  }
};

/// Defaults overridden by the YAML file (if not empty); validated. Throws semap::Error.
SemapConfig load_semap_config(const std::filesystem::path& yaml_path);
/// YAML text of the defaults with docs.
std::string dump_default_config();

}  // namespace semap
