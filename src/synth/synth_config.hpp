#pragma once
// Configuration of the synthetic world (`semap synth`): scene size, object count, trajectory,
// image size and the realism options (depth noise, noisy segmentation).
#include <cstdint>
#include <filesystem>

#include "semap/core/params.hpp"
#include "synth/depth_noise.hpp"
#include "semap/synth/segmentation_noise.hpp"

namespace semap {

struct SynthConfig {
  int frames = 300;            ///< number of frames (the trajectory is one closed loop)
  uint64_t seed = 1;           ///< scene layout, textures and noise all follow from it
  int objects = 12;            ///< object instances (the first K of a fixed class sequence)
  bool depth_noise = false;    ///< apply the Kinect-like depth noise model to depth/
  double seg_noise = 0.0;      ///< > 0: also write label_noisy/ instance_noisy/ with this flicker rate
  int width = 640, height = 480;
  double fps = 30.0;           ///< timestamp spacing of the frames
  double room_x = 6.0, room_y = 5.0, room_z = 2.7;  ///< room size (m)
  double camera_height = 1.4;  ///< mean camera height (m)
  double gt_point_spacing = 0.01;        ///< spacing of gt_points.ply samples (m)
  double gt_visibility_tolerance = 0.015;  ///< |rendered depth - point depth| for "observed" (m)
  DepthNoiseParams depth_noise_params;
  SegmentationNoiseParams seg_noise_params;  ///< flicker_rate is replaced by seg_noise

  void visit(ParamVisitor& v);
  void validate() const;
};

/// Renders the whole dataset into `out_dir` (layout: notes/SHARED_FORMATS.md). Writes into a
/// temporary sibling folder renamed at the end, so an interrupted run never looks complete.
/// Returns the measured renderer rate (frames/s, rendering only) and prints a progress line.
struct SynthStats {
  double render_fps = 0;     ///< frames per second of the ray caster alone (wall clock)
  double render_cpu_s_per_frame = 0;  ///< process CPU time of the ray caster per frame (all threads)
  double total_fps = 0;      ///< frames per second including noise and PNG writing
  size_t gt_points = 0;      ///< points kept in gt_points.ply
  size_t objects = 0;
};
SynthStats generate_dataset(const SynthConfig& config, const std::filesystem::path& out_dir);

}  // namespace semap

namespace semap::synth {
using semap::generate_dataset;
using semap::SynthConfig;
}  // namespace semap::synth
