#include "synth/scene.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <functional>

#include "semap/core/error.hpp"
#include "synth/random.hpp"
#include "synth/renderer.hpp"

namespace semap {
namespace {

using synth_detail::Rng;
using Eigen::Matrix3d;
using Eigen::Vector3d;
constexpr double kPi = 3.14159265358979323846;

Matrix3d yaw_rotation(double yaw) { return Eigen::AngleAxisd(yaw, Vector3d::UnitZ()).toRotationMatrix(); }

Rgb8 hsv(double h, double s, double v) {
  h = std::fmod(std::fmod(h, 1.0) + 1.0, 1.0) * 6.0;
  const int i = static_cast<int>(h) % 6;
  const double f = h - std::floor(h), p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
  double r = v, g = t, b = p;
  switch (i) {
    case 0: r = v, g = t, b = p; break;
    case 1: r = q, g = v, b = p; break;
    case 2: r = p, g = v, b = t; break;
    case 3: r = p, g = q, b = v; break;
    case 4: r = t, g = p, b = v; break;
    default: r = v, g = p, b = q; break;
  }
  auto c = [](double x) { return static_cast<uint8_t>(std::clamp(std::lround(x * 255.0), 0L, 255L)); };
  return {c(r), c(g), c(b)};
}

// A part of an object in the object's local frame (origin: footprint centre on the floor,
// x = width, +y = front, z up).
struct Part {
  PrimitiveShape shape;
  Vector3d center;
  Vector3d half;
  Matrix3d rotation = Matrix3d::Identity();
  int colour_slot = 0;  // 0 = main colour, 1 = secondary colour, 2+ = own random colour
};

struct ObjectTemplate {
  ClassId class_id;
  std::vector<Part> parts;
  Vector3d lo, hi;  // local bounds
  void compute_bounds() {
    lo = Vector3d::Constant(1e9);
    hi = Vector3d::Constant(-1e9);
    for (const Part& p : parts) {
      Primitive prim;
      prim.shape = p.shape;
      prim.center = p.center;
      prim.rotation = p.rotation;
      prim.half_size = p.half;
      for (const Vector3d& c : prim.bounds().corners()) {
        lo = lo.cwiseMin(c);
        hi = hi.cwiseMax(c);
      }
    }
  }
};

Part box_part(Vector3d lo, Vector3d hi, int slot = 0) {
  return {PrimitiveShape::kBox, (lo + hi) / 2, (hi - lo) / 2, Matrix3d::Identity(), slot};
}
Part cylinder_part(double x, double y, double z0, double z1, double r, int slot = 0) {
  return {PrimitiveShape::kCylinder, {x, y, (z0 + z1) / 2}, {r, r, (z1 - z0) / 2}, Matrix3d::Identity(), slot};
}
Part sphere_part(Vector3d c, double r, int slot = 0) {
  return {PrimitiveShape::kSphere, c, Vector3d::Constant(r), Matrix3d::Identity(), slot};
}

ObjectTemplate make_table(Rng& rng) {
  const double w = rng.uniform(1.2, 1.6), d = rng.uniform(0.7, 0.85), h = rng.uniform(0.72, 0.78);
  ObjectTemplate t{id(Label::kTable), {}, {}, {}};
  t.parts.push_back(box_part({-w / 2, -d / 2, h - 0.04}, {w / 2, d / 2, h}));
  const double leg = 0.05, inset = 0.05;
  for (int sx : {-1, 1})
    for (int sy : {-1, 1}) {
      const double cx = sx * (w / 2 - inset - leg / 2), cy = sy * (d / 2 - inset - leg / 2);
      t.parts.push_back(box_part({cx - leg / 2, cy - leg / 2, 0}, {cx + leg / 2, cy + leg / 2, h - 0.04}, 1));
    }
  return t;
}

ObjectTemplate make_chair(Rng& rng) {
  const double s = rng.uniform(0.42, 0.48), seat_h = rng.uniform(0.43, 0.47), back_h = rng.uniform(0.38, 0.5);
  ObjectTemplate t{id(Label::kChair), {}, {}, {}};
  t.parts.push_back(box_part({-s / 2, -s / 2, seat_h - 0.04}, {s / 2, s / 2, seat_h}));
  t.parts.push_back(box_part({-s / 2, -s / 2, seat_h}, {s / 2, -s / 2 + 0.04, seat_h + back_h}, 1));
  const double leg = 0.035;
  for (int sx : {-1, 1})
    for (int sy : {-1, 1}) {
      const double cx = sx * (s / 2 - leg / 2 - 0.01), cy = sy * (s / 2 - leg / 2 - 0.01);
      t.parts.push_back(box_part({cx - leg / 2, cy - leg / 2, 0}, {cx + leg / 2, cy + leg / 2, seat_h - 0.04}, 1));
    }
  return t;
}

ObjectTemplate make_sofa(Rng& rng) {
  const double w = rng.uniform(1.6, 2.0), d = rng.uniform(0.8, 0.9), h = rng.uniform(0.75, 0.85);
  const double base_h = 0.4, arm_w = 0.18, back_d = 0.2;
  ObjectTemplate t{id(Label::kSofa), {}, {}, {}};
  t.parts.push_back(box_part({-w / 2, -d / 2, 0.05}, {w / 2, d / 2, base_h}));
  t.parts.push_back(box_part({-w / 2, -d / 2, base_h}, {w / 2, -d / 2 + back_d, h}, 1));
  for (int sx : {-1, 1}) {
    const double x0 = sx < 0 ? -w / 2 : w / 2 - arm_w;
    t.parts.push_back(box_part({x0, -d / 2 + back_d, base_h}, {x0 + arm_w, d / 2, base_h + 0.22}, 1));
  }
  // Two seat cushions between the arms, a small gap between them.
  const double inner = w - 2 * arm_w, gap = 0.02, cw = (inner - gap) / 2;
  for (int i = 0; i < 2; ++i) {
    const double x0 = -w / 2 + arm_w + i * (cw + gap);
    t.parts.push_back(box_part({x0, -d / 2 + back_d, base_h}, {x0 + cw, d / 2 - 0.02, base_h + 0.1}, 2 + i));
  }
  // Short feet so the base does not sit on the floor (detail for depth edges).
  for (int sx : {-1, 1})
    for (int sy : {-1, 1})
      t.parts.push_back(cylinder_part(sx * (w / 2 - 0.08), sy * (d / 2 - 0.08), 0, 0.05, 0.025, 1));
  return t;
}

ObjectTemplate make_bookcase(Rng& rng) {
  const double w = rng.uniform(0.8, 1.0), d = rng.uniform(0.32, 0.38), h = rng.uniform(1.6, 1.9);
  const double th = 0.02;
  const int shelves = 4;
  ObjectTemplate t{id(Label::kBookcase), {}, {}, {}};
  t.parts.push_back(box_part({-w / 2, -d / 2, 0}, {-w / 2 + th, d / 2, h}));
  t.parts.push_back(box_part({w / 2 - th, -d / 2, 0}, {w / 2, d / 2, h}));
  t.parts.push_back(box_part({-w / 2 + th, -d / 2, 0}, {w / 2 - th, -d / 2 + 0.01, h - th}, 1));  // back
  t.parts.push_back(box_part({-w / 2 + th, -d / 2, h - th}, {w / 2 - th, d / 2, h}));          // top
  t.parts.push_back(box_part({-w / 2 + th, -d / 2 + 0.01, 0}, {w / 2 - th, d / 2, 0.08}));       // plinth
  const double pitch = (h - th - 0.08) / shelves;
  for (int i = 0; i < shelves; ++i) {
    const double z = 0.08 + i * pitch;
    if (i > 0) t.parts.push_back(box_part({-w / 2 + th, -d / 2 + 0.01, z - th}, {w / 2 - th, d / 2, z}));
    // Books of the bookcase (one instance with it): a row of thin boxes on each shelf.
    double x = -w / 2 + th + 0.01;
    int slot = 2;
    while (true) {
      const double bw = rng.uniform(0.025, 0.05), bh = std::min(pitch - th - 0.03, rng.uniform(0.18, 0.3));
      const double bd = rng.uniform(0.18, d - 0.05);
      if (x + bw > w / 2 - th - 0.15) break;
      t.parts.push_back(box_part({x, -d / 2 + 0.012, z}, {x + bw, -d / 2 + 0.012 + bd, z + bh}, slot++));
      x += bw + 0.002;
    }
  }
  return t;
}

ObjectTemplate make_cabinet(Rng& rng) {
  const double w = rng.uniform(0.6, 0.9), d = rng.uniform(0.42, 0.5), h = rng.uniform(0.75, 0.95);
  ObjectTemplate t{id(Label::kCabinet), {}, {}, {}};
  t.parts.push_back(box_part({-w / 2, -d / 2, 0}, {w / 2, d / 2, h}));
  for (int sx : {-1, 1}) {
    const double cx = sx * 0.06;
    t.parts.push_back(box_part({cx - 0.01, d / 2, h * 0.55}, {cx + 0.01, d / 2 + 0.025, h * 0.8}, 1));
  }
  return t;
}

ObjectTemplate make_monitor(Rng& rng) {
  const double w = rng.uniform(0.5, 0.62), h = rng.uniform(0.3, 0.36);
  ObjectTemplate t{id(Label::kMonitor), {}, {}, {}};
  t.parts.push_back(box_part({-0.11, -0.08, 0}, {0.11, 0.08, 0.015}, 1));
  t.parts.push_back(box_part({-0.02, -0.03, 0.015}, {0.02, 0.0, 0.14}, 1));
  t.parts.push_back(box_part({-w / 2, 0.0, 0.1}, {w / 2, 0.03, 0.1 + h}));
  return t;
}

ObjectTemplate make_cup(Rng& rng) {
  const double r = rng.uniform(0.035, 0.045), h = rng.uniform(0.085, 0.11);
  ObjectTemplate t{id(Label::kCup), {}, {}, {}};
  t.parts.push_back(cylinder_part(0, 0, 0, h, r));
  t.parts.push_back(box_part({r - 0.004, -0.006, h * 0.25}, {r + 0.025, 0.006, h * 0.75}));
  return t;
}

ObjectTemplate make_bottle(Rng& rng) {
  const double r = rng.uniform(0.03, 0.04), h = rng.uniform(0.16, 0.2);
  ObjectTemplate t{id(Label::kBottle), {}, {}, {}};
  t.parts.push_back(cylinder_part(0, 0, 0, h, r));
  t.parts.push_back(sphere_part({0, 0, h}, r));
  t.parts.push_back(cylinder_part(0, 0, h + r * 0.7, h + r + 0.06, 0.014));
  t.parts.push_back(cylinder_part(0, 0, h + r + 0.06, h + r + 0.08, 0.017, 1));
  return t;
}

ObjectTemplate make_box(Rng& rng) {
  const double w = rng.uniform(0.3, 0.5), d = rng.uniform(0.25, 0.4), h = rng.uniform(0.2, 0.38);
  ObjectTemplate t{id(Label::kBox), {}, {}, {}};
  t.parts.push_back(box_part({-w / 2, -d / 2, 0}, {w / 2, d / 2, h}));
  return t;
}

ObjectTemplate make_plant(Rng& rng) {
  const double pr = rng.uniform(0.13, 0.17), ph = rng.uniform(0.25, 0.35);
  ObjectTemplate t{id(Label::kPlant), {}, {}, {}};
  t.parts.push_back(cylinder_part(0, 0, 0, ph, pr, 1));
  const double fr = rng.uniform(0.2, 0.25);
  t.parts.push_back(sphere_part({0, 0, ph + fr * 0.8}, fr));
  t.parts.push_back(sphere_part({0.06, 0.04, ph + fr * 1.5}, fr * 0.75));
  return t;
}

ObjectTemplate make_lamp(Rng& rng) {
  const double h = rng.uniform(1.3, 1.6);
  ObjectTemplate t{id(Label::kLamp), {}, {}, {}};
  t.parts.push_back(cylinder_part(0, 0, 0, 0.03, 0.15, 1));
  t.parts.push_back(cylinder_part(0, 0, 0.03, h, 0.015, 1));
  t.parts.push_back(cylinder_part(0, 0, h, h + 0.25, 0.2));
  return t;
}

enum class Placement { kWall, kOnTable, kOnCabinet, kBesidePrevious };

struct Slot {
  ClassId class_id;
  Placement placement;
};

Slot furnishing_slot(int k) {
  static const Slot kFirst[] = {
      {id(Label::kTable), Placement::kWall},      {id(Label::kChair), Placement::kWall},
      {id(Label::kSofa), Placement::kWall},       {id(Label::kBookcase), Placement::kWall},
      {id(Label::kCabinet), Placement::kWall},    {id(Label::kMonitor), Placement::kOnTable},
      {id(Label::kCup), Placement::kOnTable},     {id(Label::kBottle), Placement::kOnTable},
      {id(Label::kBox), Placement::kOnCabinet},   {id(Label::kChair), Placement::kBesidePrevious},
      {id(Label::kBox), Placement::kWall},        {id(Label::kBox), Placement::kBesidePrevious},
      {id(Label::kCup), Placement::kOnTable},     {id(Label::kPlant), Placement::kWall},
      {id(Label::kLamp), Placement::kWall},
  };
  constexpr int n_first = sizeof(kFirst) / sizeof(kFirst[0]);
  if (k < n_first) return kFirst[k];
  static const Slot kCycle[] = {{id(Label::kBox), Placement::kWall},
                                {id(Label::kChair), Placement::kWall},
                                {id(Label::kBottle), Placement::kOnTable},
                                {id(Label::kCabinet), Placement::kWall}};
  return kCycle[(k - n_first) % 4];
}

ObjectTemplate make_template(ClassId c, Rng& rng) {
  switch (static_cast<Label>(c)) {
    case Label::kTable: return make_table(rng);
    case Label::kChair: return make_chair(rng);
    case Label::kSofa: return make_sofa(rng);
    case Label::kBookcase: return make_bookcase(rng);
    case Label::kCabinet: return make_cabinet(rng);
    case Label::kMonitor: return make_monitor(rng);
    case Label::kCup: return make_cup(rng);
    case Label::kBottle: return make_bottle(rng);
    case Label::kPlant: return make_plant(rng);
    case Label::kLamp: return make_lamp(rng);
    default: return make_box(rng);
  }
}

struct Placed {
  ObjectTemplate tmpl;
  Matrix3d rotation;
  Vector3d origin;  // world position of the local origin
  Obb obb;
  int wall = -1;
  Placement placement;
};

Obb world_obb(const ObjectTemplate& t, const Matrix3d& R, const Vector3d& origin) {
  Obb o;
  o.rotation = R;
  o.extent = t.hi - t.lo;
  o.center = origin + R * ((t.hi + t.lo) / 2);
  return o;
}

// Wall w (Room face order -x, +x, -y, +y): yaw that turns local +y (front) into the room.
double wall_yaw(int w) {
  switch (w) {
    case 0: return -kPi / 2;
    case 1: return kPi / 2;
    case 2: return 0.0;
    default: return kPi;
  }
}
double wall_length(int w, const Vector3d& room) { return w < 2 ? room.y() : room.x(); }
// World origin of an object whose local back (lo.y) is `gap` from wall w at position s along it.
Vector3d wall_origin(int w, const Vector3d& room, double s, double gap, const ObjectTemplate& t) {
  const double back = gap - t.lo.y();  // distance of the local origin from the wall
  switch (w) {
    case 0: return {back, room.y() - s, 0};
    case 1: return {room.x() - back, s, 0};
    case 2: return {s, back, 0};
    default: return {room.x() - s, room.y() - back, 0};
  }
}

bool inside_room(const Obb& o, const Vector3d& room) {
  for (const Vector3d& c : o.corners())
    for (int i = 0; i < 3; ++i)
      if (c[i] < -1e-9 || c[i] > room[i] + 1e-9) return false;
  return true;
}

}  // namespace

// ---- Obb ---------------------------------------------------------------------------------

std::array<Vector3d, 8> Obb::corners() const {
  std::array<Vector3d, 8> c;
  for (int i = 0; i < 8; ++i) {
    const Vector3d s((i & 1) ? 0.5 : -0.5, (i & 2) ? 0.5 : -0.5, (i & 4) ? 0.5 : -0.5);
    c[i] = center + rotation * s.cwiseProduct(extent);
  }
  return c;
}

bool Obb::contains(const Vector3d& p, double margin) const {
  const Vector3d local = rotation.transpose() * (p - center);
  for (int i = 0; i < 3; ++i)
    if (std::abs(local[i]) > extent[i] / 2 + margin) return false;
  return true;
}

bool Obb::overlaps(const Obb& other, double tolerance) const {
  // Separating axis theorem over the 15 candidate axes (Gottschalk et al. 1996).
  const Vector3d a = extent / 2, b = other.extent / 2;
  const Matrix3d R = rotation.transpose() * other.rotation;
  const Vector3d t = rotation.transpose() * (other.center - center);
  Matrix3d absR = R.cwiseAbs().array() + 1e-12;
  for (int i = 0; i < 3; ++i)
    if (std::abs(t[i]) >= a[i] + absR.row(i).dot(b) - tolerance) return false;
  for (int j = 0; j < 3; ++j)
    if (std::abs(t.dot(R.col(j))) >= absR.col(j).dot(a) + b[j] - tolerance) return false;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      const double ra = a[i1] * absR(i2, j) + a[i2] * absR(i1, j);
      const double rb = b[j1] * absR(i, j2) + b[j2] * absR(i, j1);
      const double dist = std::abs(t[i2] * R(i1, j) - t[i1] * R(i2, j));
      // Cross axes of (nearly) parallel edges are degenerate; the face axes decide then.
      const double axis_len = std::sqrt(std::max(0.0, 1.0 - R(i, j) * R(i, j)));
      if (axis_len < 1e-6) continue;
      if (dist >= ra + rb - tolerance * axis_len) return false;
    }
  return true;
}

Obb Primitive::bounds() const {
  Obb o;
  o.center = center;
  o.rotation = rotation;
  o.extent = 2 * half_size;
  return o;
}

// ---- DetailTexture -----------------------------------------------------------------------

DetailTexture::DetailTexture(uint64_t seed, int size, double texel_m)
    : size_(size), inv_texel_(static_cast<float>(1.0 / texel_m)), texels_(static_cast<size_t>(size) * size, 0.f) {
  Rng rng(synth_detail::hash_combine(seed, 0x7e87u));
  // Tileable value noise, several octaves (periods in texels).
  const int periods[] = {256, 64, 16, 4};
  const float weights[] = {0.3f, 0.3f, 0.25f, 0.15f};
  for (int o = 0; o < 4; ++o) {
    const int cells = std::max(1, size / periods[o]);
    std::vector<float> lattice(static_cast<size_t>(cells) * cells);
    for (float& v : lattice) v = static_cast<float>(rng.uniform());
    const float inv_p = 1.0f / periods[o];
    for (int y = 0; y < size; ++y) {
      const float fy = y * inv_p;
      const int y0 = static_cast<int>(fy) % cells, y1 = (y0 + 1) % cells;
      float ty = fy - std::floor(fy);
      ty = ty * ty * (3 - 2 * ty);
      for (int x = 0; x < size; ++x) {
        const float fx = x * inv_p;
        const int x0 = static_cast<int>(fx) % cells, x1 = (x0 + 1) % cells;
        float tx = fx - std::floor(fx);
        tx = tx * tx * (3 - 2 * tx);
        const float a = lattice[y0 * cells + x0] * (1 - tx) + lattice[y0 * cells + x1] * tx;
        const float b = lattice[y1 * cells + x0] * (1 - tx) + lattice[y1 * cells + x1] * tx;
        texels_[static_cast<size_t>(y) * size + x] += weights[o] * (a * (1 - ty) + b * ty);
      }
    }
  }
  // Random rectangles and discs: sharp corners and blobs for feature detectors.
  const int area_scale = (size / 256) * (size / 256);
  auto wrap = [size](int i) { return ((i % size) + size) % size; };
  for (int n = 0; n < 90 * area_scale; ++n) {
    const int x0 = rng.integer(size), y0 = rng.integer(size);
    const int w = 3 + rng.integer(28), h = 3 + rng.integer(28);
    const float value = static_cast<float>(rng.uniform());
    for (int y = y0; y < y0 + h; ++y)
      for (int x = x0; x < x0 + w; ++x) {
        float& t = texels_[static_cast<size_t>(wrap(y)) * size + wrap(x)];
        t = 0.3f * t + 0.7f * value;
      }
  }
  for (int n = 0; n < 50 * area_scale; ++n) {
    const int cx = rng.integer(size), cy = rng.integer(size), r = 2 + rng.integer(11);
    const float value = static_cast<float>(rng.uniform());
    for (int y = -r; y <= r; ++y)
      for (int x = -r; x <= r; ++x)
        if (x * x + y * y <= r * r) {
          float& t = texels_[static_cast<size_t>(wrap(cy + y)) * size + wrap(cx + x)];
          t = 0.25f * t + 0.75f * value;
        }
  }
  const auto [mn, mx] = std::minmax_element(texels_.begin(), texels_.end());
  const float lo = *mn, scale = *mx > *mn ? 1.0f / (*mx - *mn) : 1.0f;
  for (float& t : texels_) t = (t - lo) * scale;
}

float DetailTexture::sample(double u_m, double v_m) const {
  const float fu = static_cast<float>(u_m) * inv_texel_, fv = static_cast<float>(v_m) * inv_texel_;
  const float flu = std::floor(fu), flv = std::floor(fv);
  const float tu = fu - flu, tv = fv - flv;
  const int mask = size_ - 1;  // size is a power of two
  const int x0 = static_cast<int>(static_cast<int64_t>(flu) & mask), y0 = static_cast<int>(static_cast<int64_t>(flv) & mask);
  const int x1 = (x0 + 1) & mask, y1 = (y0 + 1) & mask;
  const float* row0 = &texels_[static_cast<size_t>(y0) * size_];
  const float* row1 = &texels_[static_cast<size_t>(y1) * size_];
  const float a = row0[x0] + (row0[x1] - row0[x0]) * tu;
  const float b = row1[x0] + (row1[x1] - row1[x0]) * tu;
  return a + (b - a) * tv;
}

// ---- scene -------------------------------------------------------------------------------

void SyntheticScene::build_acceleration() { accel = std::make_shared<const SceneAccel>(primitives); }

const SceneObject* SyntheticScene::find_object(uint16_t instance_id) const {
  for (const SceneObject& o : objects)
    if (o.instance_id == instance_id) return &o;
  return nullptr;
}

ClassId furnishing_class(int k) { return furnishing_slot(k).class_id; }

SyntheticScene make_empty_room(uint64_t seed, const Vector3d& room_size) {
  if (!(room_size.minCoeff() > 0.5) || !room_size.allFinite()) throw Error("synth", "room size must be > 0.5 m");
  SyntheticScene scene;
  scene.seed = seed;
  scene.room.size = room_size;
  Rng rng(synth_detail::hash_combine(seed, 0x500du));
  const double wall_hue = rng.uniform();
  for (int f = 0; f < 6; ++f) {
    double h = wall_hue, s = rng.uniform(0.1, 0.3), v = rng.uniform(0.75, 0.9);
    if (f == 4) h = rng.uniform(0.05, 0.12), s = rng.uniform(0.35, 0.6), v = rng.uniform(0.5, 0.7);  // floor
    if (f == 5) s = 0.05, v = 0.92;                                                                    // ceiling
    scene.room.colour_a[f] = hsv(h, s, v);
    scene.room.colour_b[f] = hsv(h + 0.05, std::min(1.0, s * 1.3), v * 0.45);
    scene.room.texture_offset[f] = {rng.uniform(0, 8), rng.uniform(0, 8)};
  }
  scene.texture = std::make_shared<const DetailTexture>(seed, 2048, 0.004);
  scene.build_acceleration();
  return scene;
}

SyntheticScene make_scene(uint64_t seed, int n_objects, const Vector3d& room_size) {
  if (n_objects < 0 || n_objects > kMaxSynthObjects)
    throw Error("synth", "objects must be in [0, " + std::to_string(kMaxSynthObjects) + "], got " + std::to_string(n_objects));
  SyntheticScene scene = make_empty_room(seed, room_size);
  const Vector3d& room = scene.room.size;
  // Furniture stays within this distance of its wall so the camera loop in the middle is free.
  const double max_depth_from_wall = std::min(1.0, 0.3 * std::min(room.x(), room.y()));

  for (int restart = 0;; ++restart) {
    if (restart >= 60)
      throw Error("synth", "cannot place " + std::to_string(n_objects) + " objects without overlap in the room");
    Rng rng(synth_detail::hash_combine(seed, 1000 + restart));
    std::vector<Placed> placed;
    std::vector<Obb> obstacles;

    // Door (stuff): on a random wall, with free floor space in front of it.
    const int door_wall = rng.integer(4);
    const double door_w = 0.9, door_h = 2.05;
    const double door_s = rng.uniform(0.3 + door_w / 2, wall_length(door_wall, room) - 0.3 - door_w / 2);
    ObjectTemplate door_t{id(Label::kDoor), {box_part({-door_w / 2, -0.02, 0}, {door_w / 2, 0.02, std::min(door_h, room.z() - 0.1)})}, {}, {}};
    door_t.compute_bounds();
    const Matrix3d door_R = yaw_rotation(wall_yaw(door_wall));
    const Vector3d door_origin = wall_origin(door_wall, room, door_s, -0.02, door_t);
    {
      ObjectTemplate keep_out{0, {box_part({-door_w / 2 - 0.05, 0, 0}, {door_w / 2 + 0.05, 0.7, 2.0})}, {}, {}};
      keep_out.compute_bounds();
      obstacles.push_back(world_obb(keep_out, door_R, wall_origin(door_wall, room, door_s, 0.0, keep_out)));
    }

    bool ok = true;
    for (int k = 0; k < n_objects && ok; ++k) {
      const Slot slot = furnishing_slot(k);
      ObjectTemplate t = make_template(slot.class_id, rng);
      t.compute_bounds();
      auto collides = [&](const Obb& o) {
        for (const Obb& ob : obstacles)
          if (ob.overlaps(o)) return true;
        for (const Placed& p : placed)
          if (p.obb.overlaps(o)) return true;
        return false;
      };
      Placement placement = slot.placement;
      // Supports that are missing (fewer objects) fall back to wall placement.
      const Placed* support = nullptr;
      if (placement == Placement::kOnTable || placement == Placement::kOnCabinet) {
        const ClassId want = placement == Placement::kOnTable ? id(Label::kTable) : id(Label::kCabinet);
        for (const Placed& p : placed)
          if (p.tmpl.class_id == want) {
            support = &p;
            break;
          }
        if (!support) placement = Placement::kWall;
      }
      // "Beside" = touching the latest wall-placed object of the same class (chair by chair).
      const Placed* neighbour = nullptr;
      if (placement == Placement::kBesidePrevious) {
        for (auto it = placed.rbegin(); it != placed.rend() && !neighbour; ++it)
          if (it->tmpl.class_id == slot.class_id && it->wall >= 0) neighbour = &*it;
        if (!neighbour) placement = Placement::kWall;
      }

      bool done = false;
      Placed result{t, Matrix3d::Identity(), Vector3d::Zero(), {}, -1, placement};
      for (int attempt = 0; attempt < 300 && !done; ++attempt) {
        Matrix3d R;
        Vector3d origin;
        int wall = -1;
        if (placement == Placement::kWall) {
          wall = rng.integer(4);
          const double L = wall_length(wall, room), half_w = (t.hi.x() - t.lo.x()) / 2;
          if (L < 2 * half_w + 0.1) continue;
          const double s = rng.uniform(half_w + 0.05, L - half_w - 0.05);
          R = yaw_rotation(wall_yaw(wall));
          origin = wall_origin(wall, room, s, rng.uniform(0.02, 0.08), t);
          // Centre the x extent on s (templates can be asymmetric in x).
          origin -= R * Vector3d((t.hi.x() + t.lo.x()) / 2, 0, 0);
          if (t.hi.y() - t.lo.y() + 0.08 > max_depth_from_wall) continue;
        } else if (placement == Placement::kBesidePrevious) {
          // Touching the previous object side by side: same wall and yaw, OBBs share a face.
          const Placed& prev = *neighbour;
          wall = prev.wall;
          R = prev.rotation;
          const int side = (attempt % 2 == 0) ? 1 : -1;
          const double prev_half = prev.obb.extent.x() / 2, half_w = (t.hi.x() - t.lo.x()) / 2;
          const Vector3d prev_centre_x = prev.obb.center;
          // Same back distance from the wall as the previous one.
          const Vector3d back_dir = -(R * Vector3d::UnitY());
          const double prev_back = prev.obb.extent.y() / 2;  // prev centre to its back face
          Vector3d c = prev_centre_x + side * (prev_half + half_w) * (R * Vector3d::UnitX());
          c += back_dir * (prev_back - (t.hi.y() - t.lo.y()) / 2);
          c.z() = 0;
          origin = c - R * Vector3d((t.hi.x() + t.lo.x()) / 2, (t.hi.y() + t.lo.y()) / 2, 0);
          if (attempt >= 2) break;  // no room on either side: re-draw the whole layout
        } else {
          // On top of the support, fully inside its top face (monitor at the back).
          const Obb& top = support->obb;
          const double top_z = top.center.z() + top.extent.z() / 2;
          const double yaw_s = std::atan2(top.rotation(1, 0), top.rotation(0, 0));
          const bool is_monitor = slot.class_id == id(Label::kMonitor);
          const double yaw = is_monitor ? yaw_s + rng.uniform(-0.2, 0.2) : rng.uniform(-kPi, kPi);
          R = yaw_rotation(yaw);
          const double r_xy = std::hypot(std::max(-t.lo.x(), t.hi.x()), std::max(-t.lo.y(), t.hi.y())) + 0.02;
          const double hx = top.extent.x() / 2 - r_xy, hy = top.extent.y() / 2 - r_xy;
          if (hx <= 0 || hy <= 0) continue;
          double lx = rng.uniform(-hx, hx), ly;
          if (placement == Placement::kOnTable)
            ly = is_monitor ? rng.uniform(-hy, -hy + 0.3 * hy) : rng.uniform(-0.3 * hy, hy);
          else
            ly = rng.uniform(-hy, hy);
          origin = top.center + top.rotation * Vector3d(lx, ly, 0);
          origin.z() = top_z;
        }
        const Obb o = world_obb(t, R, origin);
        if (!inside_room(o, room) || collides(o)) continue;
        result.rotation = R;
        result.origin = origin;
        result.obb = o;
        result.wall = wall;
        result.placement = placement;
        done = true;
      }
      if (!done) {
        ok = false;
        break;
      }
      placed.push_back(result);
    }
    if (!ok) continue;

    // Emit primitives: door first (stuff), then objects with instance ids 1..N.
    {
      Primitive p;
      p.shape = PrimitiveShape::kBox;
      p.center = door_origin + door_R * door_t.parts[0].center;
      p.rotation = door_R;
      p.half_size = door_t.parts[0].half;
      p.label = id(Label::kDoor);
      p.instance = 0;
      p.colour_a = hsv(0.08, 0.5, 0.6);
      p.colour_b = hsv(0.06, 0.6, 0.3);
      p.texture_offset = {rng.uniform(0, 8), rng.uniform(0, 8)};
      scene.primitives.push_back(p);
    }
    for (size_t k = 0; k < placed.size(); ++k) {
      const Placed& pl = placed[k];
      SceneObject obj;
      obj.instance_id = static_cast<uint16_t>(k + 1);
      obj.class_id = pl.tmpl.class_id;
      obj.obb = pl.obb;
      if (pl.placement == Placement::kOnTable || pl.placement == Placement::kOnCabinet) {
        // The support is the placed object directly below.
        for (size_t j = 0; j < k; ++j) {
          const Obb& s = placed[j].obb;
          const double top = s.center.z() + s.extent.z() / 2;
          if (std::abs(top - pl.origin.z()) < 1e-6 && s.contains({pl.origin.x(), pl.origin.y(), top}, 1e-6))
            obj.support = "on:" + std::to_string(j + 1);
        }
      } else {
        obj.support = "floor";
      }
      const double hue = rng.uniform();
      const Rgb8 main_a = hsv(hue, rng.uniform(0.45, 0.85), rng.uniform(0.55, 0.9));
      const Rgb8 main_b = hsv(hue + 0.04, rng.uniform(0.5, 0.9), rng.uniform(0.2, 0.4));
      const double hue2 = hue + rng.uniform(0.2, 0.8);
      const Rgb8 sec_a = hsv(hue2, rng.uniform(0.2, 0.6), rng.uniform(0.4, 0.8));
      const Rgb8 sec_b = hsv(hue2, rng.uniform(0.3, 0.7), rng.uniform(0.1, 0.3));
      for (const Part& part : pl.tmpl.parts) {
        Primitive p;
        p.shape = part.shape;
        p.center = pl.origin + pl.rotation * part.center;
        p.rotation = pl.rotation * part.rotation;
        p.half_size = part.half;
        p.label = pl.tmpl.class_id;
        p.instance = obj.instance_id;
        if (part.colour_slot == 0) {
          p.colour_a = main_a, p.colour_b = main_b;
        } else if (part.colour_slot == 1) {
          p.colour_a = sec_a, p.colour_b = sec_b;
        } else {
          const double h = rng.uniform();
          p.colour_a = hsv(h, rng.uniform(0.4, 0.9), rng.uniform(0.5, 0.9));
          p.colour_b = hsv(h, rng.uniform(0.4, 0.9), rng.uniform(0.15, 0.35));
        }
        p.texture_offset = {rng.uniform(0, 8), rng.uniform(0, 8)};
        obj.primitives.push_back(static_cast<uint32_t>(scene.primitives.size()));
        scene.primitives.push_back(p);
      }
      scene.objects.push_back(std::move(obj));
    }
    break;
  }
  scene.build_acceleration();
  return scene;
}

}  // namespace semap
