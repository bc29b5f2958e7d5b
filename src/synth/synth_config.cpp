#include "synth/synth_config.hpp"

#include "synth/scene.hpp"

namespace semap {

void SynthConfig::visit(ParamVisitor& v) {
  v.param("frames", frames, "frames", "number of frames (one closed camera loop)");
  int seed_int = static_cast<int>(seed);
  v.param("seed", seed_int, "", "layout, textures and noise follow from it");
  seed = static_cast<uint64_t>(static_cast<uint32_t>(seed_int));
  v.param("objects", objects, "", "object instances (first K of the fixed furnishing sequence)");
  v.param("depth_noise", depth_noise, "", "apply the Kinect-like depth noise model");
  v.param("seg_noise", seg_noise, "", "> 0: also write label_noisy/ instance_noisy/ with this flicker rate");
  v.param("width", width, "px", "image width");
  v.param("height", height, "px", "image height");
  v.param("fps", fps, "1/s", "frame rate of the timestamps");
  v.param("room_x", room_x, "m", "room size along x");
  v.param("room_y", room_y, "m", "room size along y");
  v.param("room_z", room_z, "m", "room height");
  v.param("camera_height", camera_height, "m", "mean camera height");
  v.param("gt_point_spacing", gt_point_spacing, "m", "spacing of the gt_points.ply samples");
  v.param("gt_visibility_tolerance", gt_visibility_tolerance, "m",
          "a gt point counts as observed when a frame's clean depth agrees within this");
  v.section("depth_noise_model", "Kinect-like depth noise", [&](ParamVisitor& s) { depth_noise_params.visit(s); });
  v.section("segmentation_noise", "noisy segmentation mode", [&](ParamVisitor& s) { seg_noise_params.visit(s); });
}

void SynthConfig::validate() const {
  require_param(frames >= 1 && frames <= 1000000, "frames", "must be in [1, 1000000]");
  require_param(objects >= 0 && objects <= kMaxSynthObjects, "objects",
                "must be in [0, " + std::to_string(kMaxSynthObjects) + "]");
  require_param(seg_noise >= 0 && seg_noise <= 1, "seg_noise", "must be in [0, 1]");
  require_param(width >= 16 && width <= 8192 && height >= 16 && height <= 8192, "width/height", "must be in [16, 8192]");
  require_param(fps > 0, "fps", "must be > 0");
  require_param(room_x >= 4.5 && room_y >= 4.0 && room_z >= 2.2 && room_x <= 50 && room_y <= 50 && room_z <= 10, "room",
                "room must be at least 4.5 x 4.0 x 2.2 m and at most 50 x 50 x 10 m");
  require_param(camera_height > 0.3 && camera_height < room_z - 0.3, "camera_height", "must be inside the room");
  require_param(gt_point_spacing >= 0.002 && gt_point_spacing <= 0.2, "gt_point_spacing", "must be in [0.002, 0.2] m");
  require_param(gt_visibility_tolerance > 0, "gt_visibility_tolerance", "must be > 0");
  seg_noise_params.validate();
}

}  // namespace semap
