#include "synth/renderer.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "semap/core/error.hpp"

namespace semap {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kEps = 1e-5f;

// Ray/slab test against a node box; returns the entry distance or +inf.
inline float node_entry(const SceneAccel::Node& n, const float o[3], const float inv[3], float t_max) {
  float t0 = 0.f, t1 = t_max;
  for (int a = 0; a < 3; ++a) {
    float ta = (n.lo[a] - o[a]) * inv[a], tb = (n.hi[a] - o[a]) * inv[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = ta > t0 ? ta : t0;
    t1 = tb < t1 ? tb : t1;
    if (t0 > t1) return kInf;
  }
  return t0;
}

// Intersects one primitive in its local frame; updates t_best and the local normal on a hit.
inline bool intersect_geom(const SceneAccel::Geom& g, const float o[3], const float d[3], float& t_best,
                           float nl[3]) {
  // local = R^T (p - c); r is world_from_local row-major, so R^T row i = column i of r.
  const float px = o[0] - g.c[0], py = o[1] - g.c[1], pz = o[2] - g.c[2];
  const float lo[3] = {g.r[0] * px + g.r[3] * py + g.r[6] * pz, g.r[1] * px + g.r[4] * py + g.r[7] * pz,
                       g.r[2] * px + g.r[5] * py + g.r[8] * pz};
  const float ld[3] = {g.r[0] * d[0] + g.r[3] * d[1] + g.r[6] * d[2], g.r[1] * d[0] + g.r[4] * d[1] + g.r[7] * d[2],
                       g.r[2] * d[0] + g.r[5] * d[1] + g.r[8] * d[2]};
  if (g.shape == static_cast<uint8_t>(PrimitiveShape::kBox)) {
    float t0 = -kInf, t1 = kInf;
    int axis = 0;
    for (int a = 0; a < 3; ++a) {
      if (std::abs(ld[a]) < 1e-12f) {
        if (std::abs(lo[a]) > g.h[a]) return false;
        continue;
      }
      const float inv = 1.f / ld[a];
      float ta = (-g.h[a] - lo[a]) * inv, tb = (g.h[a] - lo[a]) * inv;
      if (ta > tb) std::swap(ta, tb);
      if (ta > t0) t0 = ta, axis = a;
      if (tb < t1) t1 = tb;
    }
    if (t0 > t1 || t0 <= kEps || t0 >= t_best) return false;
    t_best = t0;
    nl[0] = nl[1] = nl[2] = 0.f;
    nl[axis] = ld[axis] > 0 ? -1.f : 1.f;
    return true;
  }
  if (g.shape == static_cast<uint8_t>(PrimitiveShape::kSphere)) {
    const float r = g.h[0];
    const float a = ld[0] * ld[0] + ld[1] * ld[1] + ld[2] * ld[2];
    const float b = lo[0] * ld[0] + lo[1] * ld[1] + lo[2] * ld[2];
    const float c = lo[0] * lo[0] + lo[1] * lo[1] + lo[2] * lo[2] - r * r;
    const float disc = b * b - a * c;
    if (disc < 0) return false;
    const float t = (-b - std::sqrt(disc)) / a;
    if (t <= kEps || t >= t_best) return false;
    t_best = t;
    const float inv_r = 1.f / r;
    for (int i = 0; i < 3; ++i) nl[i] = (lo[i] + t * ld[i]) * inv_r;
    return true;
  }
  // Cylinder along local z: side then caps.
  const float r = g.h[0], hh = g.h[2];
  bool hit = false;
  const float a = ld[0] * ld[0] + ld[1] * ld[1];
  if (a > 1e-12f) {
    const float b = lo[0] * ld[0] + lo[1] * ld[1];
    const float c = lo[0] * lo[0] + lo[1] * lo[1] - r * r;
    const float disc = b * b - a * c;
    if (disc >= 0) {
      const float t = (-b - std::sqrt(disc)) / a;
      const float z = lo[2] + t * ld[2];
      if (t > kEps && t < t_best && std::abs(z) <= hh) {
        t_best = t;
        const float inv_r = 1.f / r;
        nl[0] = (lo[0] + t * ld[0]) * inv_r;
        nl[1] = (lo[1] + t * ld[1]) * inv_r;
        nl[2] = 0.f;
        hit = true;
      }
    }
  }
  if (std::abs(ld[2]) > 1e-12f) {
    const float cap = ld[2] > 0 ? -hh : hh;  // the cap facing the ray
    const float t = (cap - lo[2]) / ld[2];
    if (t > kEps && t < t_best) {
      const float x = lo[0] + t * ld[0], y = lo[1] + t * ld[1];
      if (x * x + y * y <= r * r) {
        t_best = t;
        nl[0] = nl[1] = 0.f;
        nl[2] = cap > 0 ? 1.f : -1.f;
        hit = true;
      }
    }
  }
  return hit;
}

struct BuildItem {
  Eigen::Vector3f lo, hi, centroid;
  int32_t index;
};

void build_node(std::vector<SceneAccel::Node>& nodes, std::vector<BuildItem>& items, int begin, int end,
                int node_index) {
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(kInf), hi = Eigen::Vector3f::Constant(-kInf);
  Eigen::Vector3f clo = lo, chi = hi;
  for (int i = begin; i < end; ++i) {
    lo = lo.cwiseMin(items[i].lo);
    hi = hi.cwiseMax(items[i].hi);
    clo = clo.cwiseMin(items[i].centroid);
    chi = chi.cwiseMax(items[i].centroid);
  }
  SceneAccel::Node& n = nodes[node_index];
  for (int a = 0; a < 3; ++a) n.lo[a] = lo[a], n.hi[a] = hi[a];
  if (end - begin <= 2) {
    n.left_or_first = begin;
    n.count = end - begin;
    return;
  }
  int axis = 0;
  (chi - clo).maxCoeff(&axis);
  const int mid = (begin + end) / 2;
  std::nth_element(items.begin() + begin, items.begin() + mid, items.begin() + end,
                   [axis](const BuildItem& x, const BuildItem& y) { return x.centroid[axis] < y.centroid[axis]; });
  const int left = static_cast<int>(nodes.size());
  nodes.push_back({});
  nodes.push_back({});
  nodes[node_index].left_or_first = left;
  nodes[node_index].count = 0;
  build_node(nodes, items, begin, mid, left);
  build_node(nodes, items, mid, end, left + 1);
}

// Room face hit from inside: the exit face of the ray from the room box.
inline bool room_exit(const Eigen::Vector3d& size, const float o[3], const float d[3], float& t, int& face) {
  t = kInf;
  face = -1;
  for (int a = 0; a < 3; ++a) {
    if (d[a] > 0) {
      const float ta = (static_cast<float>(size[a]) - o[a]) / d[a];
      if (ta < t) t = ta, face = 2 * a + 1;
    } else if (d[a] < 0) {
      const float ta = -o[a] / d[a];
      if (ta < t) t = ta, face = 2 * a;
    }
  }
  // Room face order: -x, +x, -y, +y, floor (-z), ceiling (+z) == 2a (+1 for the max side).
  return face >= 0 && t > 0;
}

ClassId room_label(int face) {
  if (face == 4) return id(Label::kFloor);
  if (face == 5) return id(Label::kCeiling);
  return id(Label::kWall);
}

Eigen::Vector3d room_normal(int face) {
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  n[face / 2] = (face % 2 == 0) ? 1.0 : -1.0;  // pointing into the room
  return n;
}

uint8_t to_byte(double x) { return static_cast<uint8_t>(std::lround(std::clamp(x, 0.0, 255.0))); }

}  // namespace

SceneAccel::SceneAccel(const std::vector<Primitive>& primitives) {
  std::vector<BuildItem> items;
  items.reserve(primitives.size());
  for (size_t i = 0; i < primitives.size(); ++i) {
    Eigen::Vector3f lo = Eigen::Vector3f::Constant(kInf), hi = Eigen::Vector3f::Constant(-kInf);
    for (const Eigen::Vector3d& c : primitives[i].bounds().corners()) {
      lo = lo.cwiseMin(c.cast<float>());
      hi = hi.cwiseMax(c.cast<float>());
    }
    lo.array() -= 1e-4f;
    hi.array() += 1e-4f;
    items.push_back({lo, hi, (lo + hi) / 2, static_cast<int32_t>(i)});
  }
  if (items.empty()) return;
  nodes_.reserve(2 * items.size());
  nodes_.push_back({});
  build_node(nodes_, items, 0, static_cast<int>(items.size()), 0);
  for (const BuildItem& it : items) {
    const Primitive& p = primitives[it.index];
    Geom g{};
    for (int a = 0; a < 3; ++a) g.c[a] = static_cast<float>(p.center[a]), g.h[a] = static_cast<float>(p.half_size[a]);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) g.r[r * 3 + c] = static_cast<float>(p.rotation(r, c));
    g.shape = static_cast<uint8_t>(p.shape);
    geoms_.push_back(g);
    prim_index_.push_back(it.index);
  }
}

int SceneAccel::intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& dir, float t_min, float& t_max,
                          Eigen::Vector3f& normal_world) const {
  if (nodes_.empty()) return -1;
  const float o[3] = {origin.x(), origin.y(), origin.z()};
  const float d[3] = {dir.x(), dir.y(), dir.z()};
  const float inv[3] = {1.f / d[0], 1.f / d[1], 1.f / d[2]};
  int stack[64];
  int sp = 0;
  int node = 0;
  int hit_leaf = -1;
  float nl[3] = {0, 0, 0};
  (void)t_min;
  if (node_entry(nodes_[0], o, inv, t_max) == kInf) return -1;
  while (true) {
    const Node& n = nodes_[node];
    if (n.count > 0) {
      for (int i = n.left_or_first; i < n.left_or_first + n.count; ++i)
        if (intersect_geom(geoms_[i], o, d, t_max, nl)) hit_leaf = i;
    } else {
      const int l = n.left_or_first, r = l + 1;
      const float tl = node_entry(nodes_[l], o, inv, t_max), tr = node_entry(nodes_[r], o, inv, t_max);
      if (tl != kInf && tr != kInf) {
        const bool left_first = tl <= tr;
        stack[sp++] = left_first ? r : l;
        node = left_first ? l : r;
        continue;
      }
      if (tl != kInf) {
        node = l;
        continue;
      }
      if (tr != kInf) {
        node = r;
        continue;
      }
    }
    // Pop, skipping nodes now farther than the best hit.
    bool found = false;
    while (sp > 0) {
      const int cand = stack[--sp];
      if (node_entry(nodes_[cand], o, inv, t_max) != kInf) {
        node = cand;
        found = true;
        break;
      }
    }
    if (!found) break;
  }
  if (hit_leaf < 0) return -1;
  const Geom& g = geoms_[hit_leaf];
  for (int r = 0; r < 3; ++r) normal_world[r] = g.r[r * 3] * nl[0] + g.r[r * 3 + 1] * nl[1] + g.r[r * 3 + 2] * nl[2];
  return prim_index_[hit_leaf];
}

std::optional<RayHit> cast_ray(const SyntheticScene& scene, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir) {
  if (!scene.accel) throw Error("synth", "scene has no acceleration structure (call build_acceleration)");
  const float o[3] = {static_cast<float>(origin.x()), static_cast<float>(origin.y()), static_cast<float>(origin.z())};
  const float d[3] = {static_cast<float>(dir.x()), static_cast<float>(dir.y()), static_cast<float>(dir.z())};
  float t;
  int face;
  for (int a = 0; a < 3; ++a)
    if (o[a] < 0 || o[a] > scene.room.size[a]) return std::nullopt;
  if (!room_exit(scene.room.size, o, d, t, face)) return std::nullopt;
  Eigen::Vector3f n;
  const int prim = scene.accel->intersect(origin.cast<float>(), dir.cast<float>(), 0.f, t, n);
  RayHit hit;
  hit.t = t;
  hit.point = origin + static_cast<double>(t) * dir;
  if (prim >= 0) {
    hit.primitive = prim;
    hit.normal = n.cast<double>().normalized();
    hit.label = scene.primitives[prim].label;
    hit.instance = scene.primitives[prim].instance;
  } else {
    hit.room_face = face;
    hit.normal = room_normal(face);
    hit.label = room_label(face);
  }
  return hit;
}

Rgb8 surface_colour(const SyntheticScene& scene, int primitive, int room_face, const Eigen::Vector3d& point,
                    const Eigen::Vector3d& normal) {
  double u = 0, v = 0;
  Rgb8 a, b;
  if (primitive < 0) {
    const int axis = room_face / 2;
    const Eigen::Vector2d& off = scene.room.texture_offset[room_face];
    u = point[(axis + 1) % 3] + off.x();
    v = point[(axis + 2) % 3] + off.y();
    a = scene.room.colour_a[room_face];
    b = scene.room.colour_b[room_face];
  } else {
    const Primitive& p = scene.primitives[primitive];
    const Eigen::Vector3d lp = p.rotation.transpose() * (point - p.center);
    const Eigen::Vector3d ln = p.rotation.transpose() * normal;
    if (p.shape == PrimitiveShape::kBox || (p.shape == PrimitiveShape::kCylinder && std::abs(ln.z()) > 0.5)) {
      int k = 0;
      ln.cwiseAbs().maxCoeff(&k);
      u = lp[(k + 1) % 3] + 1.3 * k + (ln[k] > 0 ? 0.7 : 0.0);
      v = lp[(k + 2) % 3];
    } else {
      const double r = p.half_size.x();
      u = std::atan2(lp.y(), lp.x()) * r;
      v = lp.z();
    }
    u += p.texture_offset.x();
    v += p.texture_offset.y();
    a = p.colour_a;
    b = p.colour_b;
  }
  const float t = scene.texture ? scene.texture->sample(u, v) : 0.5f;
  // Lambert: two directional lights + ambient; view independent (METHODS-free, renderer only).
  static const Eigen::Vector3d kL1 = Eigen::Vector3d(0.35, 0.45, 1.0).normalized();
  static const Eigen::Vector3d kL2 = Eigen::Vector3d(-0.6, 0.5, 0.25).normalized();
  const double light = 0.5 + 0.4 * std::max(0.0, normal.dot(kL1)) + 0.25 * std::max(0.0, normal.dot(kL2));
  auto mix = [&](uint8_t x, uint8_t y) { return to_byte(((1 - t) * x + t * y) * light); };
  return {mix(a.r, b.r), mix(a.g, b.g), mix(a.b, b.b)};
}

PinholeIntrinsics synth_intrinsics(int width, int height) {
  PinholeIntrinsics k;
  k.width = width;
  k.height = height;
  k.fx = 525.0 * width / 640.0;
  k.fy = 525.0 * height / 480.0;
  k.cx = (width - 1) / 2.0;
  k.cy = (height - 1) / 2.0;
  return k;
}

RenderedFrame render(const SyntheticScene& scene, const Pose& T_world_camera, const PinholeIntrinsics& K) {
  if (!scene.accel) throw Error("synth", "scene has no acceleration structure (call build_acceleration)");
  if (K.width <= 0 || K.height <= 0 || K.fx <= 0 || K.fy <= 0) throw Error("synth", "bad intrinsics");
  RenderedFrame f;
  f.rgb.create(K.height, K.width, CV_8UC3);
  f.depth.create(K.height, K.width, CV_32FC1);
  f.labels.create(K.height, K.width, CV_8UC1);
  f.instances.create(K.height, K.width, CV_16UC1);
  f.cos_incidence.create(K.height, K.width, CV_32FC1);
  const Eigen::Matrix3d R = T_world_camera.linear();
  const Eigen::Vector3d origin = T_world_camera.translation();
  const Eigen::Vector3f of = origin.cast<float>();
  const float o[3] = {of.x(), of.y(), of.z()};
  bool inside = true;
  for (int a = 0; a < 3; ++a) inside = inside && origin[a] > 0 && origin[a] < scene.room.size[a];

  tbb::parallel_for(tbb::blocked_range<int>(0, K.height, 4), [&](const tbb::blocked_range<int>& rows) {
    for (int v = rows.begin(); v < rows.end(); ++v) {
      auto* rgb = f.rgb.ptr<cv::Vec3b>(v);
      auto* depth = f.depth.ptr<float>(v);
      auto* label = f.labels.ptr<uint8_t>(v);
      auto* inst = f.instances.ptr<uint16_t>(v);
      auto* cosi = f.cos_incidence.ptr<float>(v);
      const double y = (v - K.cy) / K.fy;
      for (int u = 0; u < K.width; ++u) {
        const double x = (u - K.cx) / K.fx;
        // Ray with unit camera z: its parameter t is the camera depth.
        const Eigen::Vector3d dir = R * Eigen::Vector3d(x, y, 1.0);
        const Eigen::Vector3f df = dir.cast<float>();
        const float d[3] = {df.x(), df.y(), df.z()};
        float t = kInf;
        int face = -1;
        if (!inside || !room_exit(scene.room.size, o, d, t, face)) t = kInf, face = -1;
        Eigen::Vector3f nf;
        const int prim = scene.accel->intersect(of, df, 0.f, t, nf);
        if (prim < 0 && face < 0) {
          rgb[u] = cv::Vec3b(0, 0, 0);
          depth[u] = 0.f;
          label[u] = 0;
          inst[u] = 0;
          cosi[u] = 0.f;
          continue;
        }
        const Eigen::Vector3d point = origin + static_cast<double>(t) * dir;
        Eigen::Vector3d normal;
        if (prim >= 0) {
          normal = nf.cast<double>().normalized();
          label[u] = scene.primitives[prim].label;
          inst[u] = scene.primitives[prim].instance;
        } else {
          normal = room_normal(face);
          label[u] = room_label(face);
          inst[u] = 0;
        }
        depth[u] = t;
        cosi[u] = static_cast<float>(std::abs(normal.dot(dir)) / dir.norm());
        const Rgb8 c = surface_colour(scene, prim, face, point, normal);
        rgb[u] = cv::Vec3b(c.b, c.g, c.r);
      }
    }
  });
  return f;
}

}  // namespace semap
