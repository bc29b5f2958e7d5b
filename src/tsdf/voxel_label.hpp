#pragma once
// The class a voxel shows: the one rule for the mesh's vertex labels and the labels of object
// points, so that both say the same where the evidence is thin.
#include "semap/core/labels.hpp"
#include "semap/tsdf/tsdf_map.hpp"

namespace semap {

/// A voxel's label when its evidence passes tsdf.mesh_min_label_* (METHODS A6: the Bayesian
/// argmax above mesh_min_label_probability and leading the runner-up by mesh_min_label_frames
/// frames' votes; without the Bayes layer, the compact vote with mesh_min_label_votes), else 0
/// (unlabelled). Thread safety: const, reads the map only.
class VoxelLabelRule {
 public:
  explicit VoxelLabelRule(const TsdfMap& map);
  /// The label of voxel `li` of `block` (0 when the evidence is too thin).
  ClassId label(const Block& block, int li) const;

 private:
  const TsdfMap& map_;
  bool use_bayes_;
  int bayes_stride_;
  int min_votes_;
  uint8_t max_bayes_q_;
  float min_odds_;
};

/// The label (VoxelLabelRule) of the voxel containing each point; 0 where it is unobserved.
/// Parallel (TBB); the map must not change meanwhile.
std::vector<ClassId> surface_labels(const TsdfMap& map, const std::vector<Eigen::Vector3f>& points);

}  // namespace semap
