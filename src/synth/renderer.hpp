#pragma once
// CPU ray caster for the synthetic world: a BVH over the primitives (the room's six faces are
// intersected analytically and bound every ray), TBB-parallel over image rows. Depth is the
// camera z of the nearest hit (exact to float precision), so it can be compared with the
// analytic plane depth; shading is Lambert with two directional lights plus ambient, view
// independent, so a surface has the same colour in every frame.
#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "semap/core/camera.hpp"
#include "semap/core/labels.hpp"
#include "semap/core/pose.hpp"
#include "synth/scene.hpp"

namespace semap {

struct RenderedFrame {
  cv::Mat rgb;            ///< CV_8UC3 BGR
  cv::Mat depth;          ///< CV_32FC1 metres (camera z), 0 = no surface
  cv::Mat labels;         ///< CV_8UC1 project class ids
  cv::Mat instances;      ///< CV_16UC1, 0 = stuff
  cv::Mat cos_incidence;  ///< CV_32FC1 |cos| of ray/normal angle (for the depth noise model)
};

struct RayHit {
  double t = 0;            ///< ray parameter (camera z for rays with unit camera z)
  int primitive = -1;      ///< index into scene.primitives, -1 = room face
  int room_face = -1;      ///< 0..5 (Room order) when primitive == -1
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  ///< world, facing the ray origin side
  ClassId label = 0;
  uint16_t instance = 0;
};

/// BVH over the scene's primitives (median split on the widest centroid axis, leaves <= 2).
class SceneAccel {
 public:
  explicit SceneAccel(const std::vector<Primitive>& primitives);
  /// Nearest hit with t in (t_min, t_max); -1 when none. Sets t and the hit's local normal.
  int intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& dir, float t_min, float& t_max,
                Eigen::Vector3f& normal_world) const;
  size_t node_count() const { return nodes_.size(); }

  struct Node {
    float lo[3], hi[3];
    int32_t left_or_first;  ///< child index (inner) or first primitive (leaf)
    int32_t count;          ///< 0 = inner node
  };
  struct Geom {
    float c[3];
    float r[9];  ///< world_from_local, row-major
    float h[3];
    uint8_t shape;
  };

 private:
  std::vector<Node> nodes_;
  std::vector<Geom> geoms_;           ///< in BVH leaf order
  std::vector<int32_t> prim_index_;   ///< leaf order -> scene primitive index
};

/// Casts one ray (world frame); nullopt when nothing is hit (outside the room).
std::optional<RayHit> cast_ray(const SyntheticScene& scene, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir);

/// Shaded colour of a surface point (same as the rendered pixel); BGR order is applied by render().
Rgb8 surface_colour(const SyntheticScene& scene, int primitive, int room_face, const Eigen::Vector3d& point,
                    const Eigen::Vector3d& normal);

/// Renders one frame at pose T_world_camera (camera x right, y down, z forward).
/// Throws semap::Error when the scene has no acceleration structure.
RenderedFrame render(const SyntheticScene& scene, const Pose& T_world_camera, const PinholeIntrinsics& intrinsics);

/// 525/525/319.5/239.5 at 640x480, scaled for other sizes.
PinholeIntrinsics synth_intrinsics(int width = 640, int height = 480);

}  // namespace semap
