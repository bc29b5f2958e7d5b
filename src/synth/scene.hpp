#pragma once
// The procedural indoor room of the synthetic world: an axis-aligned room (floor z = 0, walls,
// ceiling; world z up, metres) furnished with objects built from primitives (oriented boxes,
// cylinders, spheres). Each object is one instance (id >= 1) of a project class; walls, floor,
// ceiling and the door are stuff (instance 0).
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "semap/core/labels.hpp"

namespace semap {

/// Oriented box; extent = full side lengths, rotation = world_from_box (columns = box axes).
struct Obb {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d extent = Eigen::Vector3d::Zero();
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();

  /// Separating-axis test; boxes that only touch (penetration <= tolerance) do not overlap.
  bool overlaps(const Obb& other, double tolerance = 1e-6) const;
  std::array<Eigen::Vector3d, 8> corners() const;
  bool contains(const Eigen::Vector3d& p, double margin = 0.0) const;
};

enum class PrimitiveShape : uint8_t { kBox, kCylinder, kSphere };

struct Primitive {
  PrimitiveShape shape = PrimitiveShape::kBox;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  ///< world_from_local; cylinder axis = local z
  /// Box: half side lengths; cylinder: (radius, radius, half height); sphere: (r, r, r).
  Eigen::Vector3d half_size = Eigen::Vector3d::Constant(0.1);
  ClassId label = 0;
  uint16_t instance = 0;
  Rgb8 colour_a, colour_b;                       ///< albedo blended by the texture value
  Eigen::Vector2d texture_offset = Eigen::Vector2d::Zero();  ///< m, decorrelates surfaces

  /// Oriented bounding box of the primitive.
  Obb bounds() const;
};

struct SceneObject {
  uint16_t instance_id = 0;
  ClassId class_id = 0;
  Obb obb;                          ///< tight box of all its primitives, object-aligned
  std::vector<uint32_t> primitives; ///< indices into SyntheticScene::primitives
  std::string support = "floor";    ///< "floor", "wall" or "on:<instance id>"
};

/// Room [0, size.x] x [0, size.y] x [0, size.z]; face order: -x, +x, -y, +y, floor, ceiling.
struct Room {
  Eigen::Vector3d size{6.0, 5.0, 2.7};
  std::array<Rgb8, 6> colour_a{}, colour_b{};
  std::array<Eigen::Vector2d, 6> texture_offset{};
};

/// Procedural grey-level detail texture (value noise octaves + random rectangles and discs),
/// tiled; sampled in metres. High-frequency corners make ORB tracking work.
class DetailTexture {
 public:
  DetailTexture(uint64_t seed, int size = 1024, double texel_m = 0.004);
  /// Bilinear sample in [0, 1] at surface coordinates (u, v) in metres.
  float sample(double u_m, double v_m) const;
  int size() const { return size_; }

 private:
  int size_;
  float inv_texel_;
  std::vector<float> texels_;
};

class SceneAccel;  // BVH over primitives (synth/renderer.hpp)

struct SyntheticScene {
  uint64_t seed = 0;
  Room room;
  std::vector<Primitive> primitives;   ///< object parts and stuff parts (door)
  std::vector<SceneObject> objects;    ///< instance ids 1..N in order
  std::shared_ptr<const DetailTexture> texture;
  std::shared_ptr<const SceneAccel> accel;

  /// (Re)builds the BVH; call after changing `primitives`. make_scene() already did.
  void build_acceleration();
  const SceneObject* find_object(uint16_t instance_id) const;
};

/// The class of the k-th object (0-based) of the fixed furnishing sequence: the first 10 are
/// table, chair, sofa, bookcase, cabinet, monitor (on the table), cup (on the table), bottle
/// (on the table), box (on the cabinet), chair (touching the first chair); then box, box
/// (touching), cup, plant, lamp, and further boxes/chairs/cups/bottles.
ClassId furnishing_class(int k);

/// A furnished room; deterministic for `seed`. Throws semap::Error when `objects` cannot be
/// placed without interpenetration (more than kMaxSynthObjects).
SyntheticScene make_scene(uint64_t seed, int objects = 12, const Eigen::Vector3d& room_size = {6.0, 5.0, 2.7});
/// An empty room (no objects, no door) with textures; for renderer tests.
SyntheticScene make_empty_room(uint64_t seed, const Eigen::Vector3d& room_size = {6.0, 5.0, 2.7});

constexpr int kMaxSynthObjects = 30;  // 30 fit in the default room for every seed tried

}  // namespace semap
