#pragma once
// The class a voxel shows: the one rule for the mesh's vertex labels and the labels of object
// points, so that both say the same where the evidence is thin.
#include <array>
#include <vector>

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

/// The fused class distribution of the voxel containing each of a mesh's vertices, for deciding a
/// label when the surface's geometry rules some classes out (tsdf/label_priors.hpp): the
/// posterior conditioned on those classes being impossible, decided by VoxelLabelRule's
/// thresholds. Empty when the map has no Bayesian layer. Thread safety: const after construction.
class SurfaceLabelEvidence {
 public:
  SurfaceLabelEvidence() = default;
  /// Copies the Bayesian layer's bytes at each point, or, where its voxel was never labelled, of
  /// the nearest labelled voxel along the normal within tsdf.label_evidence_reach_voxels that lies
  /// no nearer another surface (TBB); the map must not change meanwhile.
  SurfaceLabelEvidence(const TsdfMap& map, const std::vector<Eigen::Vector3f>& points);
  bool empty() const { return bytes_.empty(); }
  size_t size() const { return stride_ > 0 ? bytes_.size() / stride_ : 0; }
  /// The label of point i when every class c with ruled_out[c] cannot be there: the most probable
  /// remaining class, shown when its conditioned probability reaches mesh_min_label_probability
  /// and it leads the remaining runner-up by mesh_min_label_frames frames' votes; else 0.
  ClassId label_excluding(size_t i, const std::array<bool, kNumClasses>& ruled_out) const;
  /// The likely class of point i where the evidence is too thin for label_excluding: the class c
  /// not ruled out that maximises p(c | evidence) * scene_prior[c] (the map's own class
  /// frequencies, so that a class the map shows nowhere needs strong evidence), when it holds
  /// min_probability of that product's sum and leads the runner-up; else 0 (also when never labelled).
  ClassId likely_excluding(size_t i, const std::array<bool, kNumClasses>& ruled_out,
                           const std::array<float, kNumClasses>& scene_prior, float min_probability) const;

 private:
  BayesLayerCodec codec_;
  int stride_ = 0;
  std::vector<uint8_t> bytes_;
  float min_probability_ = 1.0f, min_odds_ = 0.0f;
};

/// The label (VoxelLabelRule) of the voxel containing each point; 0 where it is unobserved.
/// Parallel (TBB); the map must not change meanwhile.
std::vector<ClassId> surface_labels(const TsdfMap& map, const std::vector<Eigen::Vector3f>& points);

}  // namespace semap
