#include "synth/synth_config.hpp"

#include "synth/scene.hpp"

namespace semap {

void SynthConfig::visit(ParamVisitor& v) {
  v.param("frames", frames, "frames", "number of frames (one closed camera loop)", {1, 1000000});
  int seed_int = static_cast<int>(seed);
  v.param("seed", seed_int, "", "layout, textures and noise follow from it");
  seed = static_cast<uint64_t>(static_cast<uint32_t>(seed_int));
  v.param("objects", objects, "", "object instances (first K of the fixed furnishing sequence)", {0, kMaxSynthObjects});
  v.param("depth_noise", depth_noise, "", "apply the Kinect-like depth noise model");
  v.param("seg_noise", seg_noise, "", "> 0: also write label_noisy/ instance_noisy/ with this flicker rate", fraction());
  v.param("width", width, "px", "image width", {16, 8192});
  v.param("height", height, "px", "image height", {16, 8192});
  v.param("fps", fps, "1/s", "frame rate of the timestamps", positive(1000.0));
  v.param("room_x", room_x, "m", "room size along x", {4.5, 50.0});
  v.param("room_y", room_y, "m", "room size along y", {4.0, 50.0});
  v.param("room_z", room_z, "m", "room height", {2.2, 10.0});
  v.param("camera_height", camera_height, "m", "mean camera height (inside the room, 0.3 m from floor and ceiling)", {0.3, 9.7, true});
  v.param("gt_point_spacing", gt_point_spacing, "m", "spacing of the gt_points.ply samples", {0.002, 0.2});
  v.param("gt_visibility_tolerance", gt_visibility_tolerance, "m",
          "a gt point counts as observed when a frame's clean depth agrees within this", positive(1.0));
  v.section("depth_noise_model", "Kinect-like depth noise", [&](ParamVisitor& s) { depth_noise_params.visit(s); });
  v.section("segmentation_noise", "noisy segmentation mode", [&](ParamVisitor& s) { seg_noise_params.visit(s); });
}

void SynthConfig::validate() const {
  check_param_ranges(*this, "");
  require_param(camera_height < room_z - 0.3, "camera_height", "must be inside the room (0.3 m below room_z)");
}

}  // namespace semap
