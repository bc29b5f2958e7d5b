#pragma once
// TSDF integrators behind one interface (METHODS.md B5, B6), created by name:
//   "grouped"    semantic grouped ray casting (B5) with the Voxblox update (B6)
//   "projective" every voxel of the touched blocks projected into the depth image (nvblox/Open3D)
// Both are parallel (TBB) and deterministic for any thread count: work is partitioned per block
// and each block applies its updates in a fixed order.
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "semap/core/camera.hpp"
#include "semap/core/pose.hpp"
#include "semap/tsdf/tsdf_map.hpp"

namespace semap {

/// One frame to integrate. Only `depth` is required; every image is registered to depth.
struct IntegrationInput {
  cv::Mat depth;          ///< CV_32FC1 metres; NaN/0/< tsdf.min_depth / > max_depth skipped
  PinholeIntrinsics intrinsics;
  Pose T_world_camera = Pose::Identity();
  cv::Mat labels;         ///< optional CV_8UC1 project class ids, 0 = no label (geometry only)
  cv::Mat confidence;     ///< optional CV_32FC1 in (0, 1]: P(label) for the Bayesian layer
  cv::Mat probabilities;  ///< optional CV_32FC(n) per-class probabilities (channel = class id)
  cv::Mat colour;         ///< optional CV_8UC3 BGR
};

struct IntegrationStats {
  size_t valid_pixels = 0;
  size_t rays = 0;            ///< groups (grouped) or 0 (projective)
  size_t voxel_updates = 0;
  size_t touched_blocks = 0;
  size_t allocated_blocks = 0;  ///< new this frame
};

class Integrator {
 public:
  virtual ~Integrator() = default;
  virtual std::string name() const = 0;
  /// Fuses one frame into `map`. Throws semap::Error("integrate", ...) on inconsistent input.
  virtual void integrate(TsdfMap& map, const IntegrationInput& input) = 0;
  const IntegrationStats& last_stats() const { return stats_; }
  /// CPU milliseconds TBB worker threads spent integrating so far (the calling thread's own
  /// CPU not included): the pipeline's per-stage CPU budget (issue 20).
  virtual double worker_cpu_ms() const { return 0.0; }

 protected:
  IntegrationStats stats_;
};

std::unique_ptr<Integrator> make_integrator(IntegratorKind kind, const TsdfConfig& config);

// ---- METHODS B5 grouping, exposed for tests ----

/// One measured point with its B5 weight w(p) = 1/z^2.
struct LabelledPoint {
  Eigen::Vector3f position;
  float weight = 1.0f;
  ClassId label = 0;
};
/// Result of grouping the points that fall into one voxel.
struct PointGroup {
  ClassId label = 0;               ///< argmax_l W_l (ties: lower id)
  Eigen::Vector3f point;           ///< weighted mean of the points WITH that label
  float label_weight = 0.0f;       ///< W_label
  float total_weight = 0.0f;       ///< sum of all point weights (the ray weight of B6)
};
/// B5 on one voxel's points (the integrator runs the same rule through a hash of groups).
PointGroup group_points(const std::vector<LabelledPoint>& points);

}  // namespace semap
