#include "synth/gt_points.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>

#include "semap/core/error.hpp"
#include "synth/renderer.hpp"

namespace semap {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct Sampler {
  const SyntheticScene& scene;
  PointCloud& cloud;
  void add(int primitive, int room_face, const Eigen::Vector3d& p, const Eigen::Vector3d& n, ClassId label,
           uint16_t instance) {
    cloud.points.push_back(p.cast<float>());
    cloud.normals.push_back(n.cast<float>());
    cloud.colours.push_back(surface_colour(scene, primitive, room_face, p, n));
    cloud.labels.push_back(label);
    cloud.instances.push_back(instance);
  }
};

int steps(double length, double spacing) { return std::max(1, static_cast<int>(std::ceil(length / spacing - 1e-9))); }

// Grid over a rectangle centred at `c` spanned by half-axes a (along e1) and b (along e2).
template <class F>
void grid(double a, double b, double spacing, F&& emit) {
  const int n1 = steps(2 * a, spacing), n2 = steps(2 * b, spacing);
  for (int i = 0; i < n1; ++i)
    for (int j = 0; j < n2; ++j) emit(-a + (i + 0.5) * 2 * a / n1, -b + (j + 0.5) * 2 * b / n2);
}

}  // namespace

PointCloud sample_scene_surface(const SyntheticScene& scene, double spacing) {
  if (!(spacing > 1e-4)) throw Error("synth", "gt point spacing must be > 0.1 mm");
  PointCloud cloud;
  Sampler s{scene, cloud};
  const Eigen::Vector3d& size = scene.room.size;
  // Room faces (normals into the room).
  for (int face = 0; face < 6; ++face) {
    const int axis = face / 2, a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    n[axis] = face % 2 == 0 ? 1 : -1;
    const ClassId label = face == 4 ? id(Label::kFloor) : face == 5 ? id(Label::kCeiling) : id(Label::kWall);
    grid(size[a1] / 2, size[a2] / 2, spacing, [&](double x, double y) {
      Eigen::Vector3d p;
      p[axis] = face % 2 == 0 ? 0.0 : size[axis];
      p[a1] = size[a1] / 2 + x;
      p[a2] = size[a2] / 2 + y;
      s.add(-1, face, p, n, label, 0);
    });
  }
  for (size_t pi = 0; pi < scene.primitives.size(); ++pi) {
    const Primitive& prim = scene.primitives[pi];
    const int idx = static_cast<int>(pi);
    const Eigen::Vector3d& h = prim.half_size;
    auto world = [&](const Eigen::Vector3d& local) -> Eigen::Vector3d { return prim.center + prim.rotation * local; };
    auto add_local = [&](const Eigen::Vector3d& lp, const Eigen::Vector3d& ln) {
      s.add(idx, -1, world(lp), prim.rotation * ln, prim.label, prim.instance);
    };
    switch (prim.shape) {
      case PrimitiveShape::kBox:
        for (int k = 0; k < 3; ++k)
          for (int sign : {-1, 1}) {
            const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
            Eigen::Vector3d n = Eigen::Vector3d::Zero();
            n[k] = sign;
            grid(h[k1], h[k2], spacing, [&](double x, double y) {
              Eigen::Vector3d lp;
              lp[k] = sign * h[k];
              lp[k1] = x;
              lp[k2] = y;
              add_local(lp, n);
            });
          }
        break;
      case PrimitiveShape::kCylinder: {
        const double r = h.x(), hh = h.z();
        const int nt = steps(2 * kPi * r, spacing), nz = steps(2 * hh, spacing);
        for (int i = 0; i < nt; ++i) {
          const double a = (i + 0.5) * 2 * kPi / nt;
          const Eigen::Vector3d n(std::cos(a), std::sin(a), 0);
          for (int j = 0; j < nz; ++j) add_local(Eigen::Vector3d(r * n.x(), r * n.y(), -hh + (j + 0.5) * 2 * hh / nz), n);
        }
        for (int sign : {-1, 1})
          grid(r, r, spacing, [&](double x, double y) {
            if (x * x + y * y <= r * r) add_local({x, y, sign * hh}, {0, 0, static_cast<double>(sign)});
          });
        break;
      }
      case PrimitiveShape::kSphere: {
        const double r = h.x();
        const int nlat = steps(kPi * r, spacing);
        for (int i = 0; i < nlat; ++i) {
          const double phi = -kPi / 2 + (i + 0.5) * kPi / nlat;
          const int nlon = steps(2 * kPi * r * std::cos(phi), spacing);
          for (int j = 0; j < nlon; ++j) {
            const double lam = (j + 0.5) * 2 * kPi / nlon;
            const Eigen::Vector3d n(std::cos(phi) * std::cos(lam), std::cos(phi) * std::sin(lam), std::sin(phi));
            add_local(r * n, n);
          }
        }
        break;
      }
    }
  }
  return cloud;
}

void mark_observed_points(const PointCloud& cloud, const cv::Mat& depth, const Pose& T_world_camera,
                          const PinholeIntrinsics& K, double tolerance, std::vector<uint8_t>& observed) {
  if (depth.type() != CV_32FC1) throw Error("synth", "mark_observed_points needs CV_32FC1 depth");
  observed.resize(cloud.size(), 0);
  const Eigen::Matrix4f T_cw = T_world_camera.inverse().matrix().cast<float>();
  const Eigen::Matrix3f R = T_cw.block<3, 3>(0, 0);
  const Eigen::Vector3f t = T_cw.block<3, 1>(0, 3);
  const float fx = K.fx, fy = K.fy, cx = K.cx, cy = K.cy, tol = tolerance;
  const bool with_normals = cloud.has_normals();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, cloud.size(), 16384), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      if (observed[i]) continue;
      const Eigen::Vector3f pc = R * cloud.points[i] + t;
      if (pc.z() < 0.05f) continue;
      // A face pointing away from the camera is never seen, however close it lies behind the
      // visible one (the back of a 1.5 cm panel, a shelf's underside behind its front edge).
      if (with_normals && (R * cloud.normals[i]).dot(pc) >= 0.f) continue;
      const int u = static_cast<int>(std::lround(fx * pc.x() / pc.z() + cx));
      const int v = static_cast<int>(std::lround(fy * pc.y() / pc.z() + cy));
      if (u < 0 || v < 0 || u >= depth.cols || v >= depth.rows) continue;
      const float d = depth.at<float>(v, u);
      if (d > 0 && std::abs(d - pc.z()) < tol) observed[i] = 1;
    }
  });
}

PointCloud select_points(const PointCloud& cloud, const std::vector<uint8_t>& observed) {
  PointCloud out;
  for (size_t i = 0; i < cloud.size(); ++i)
    if (i < observed.size() && observed[i]) out.push_back_from(cloud, i);
  return out;
}

}  // namespace semap
