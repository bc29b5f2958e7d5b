#pragma once
// VCCS supervoxels (METHODS.md C2.1) of one frame's camera-frame cloud. PCL stays inside the
// .cpp (it is the slowest dependency to compile).
#include <Eigen/Core>
#include <vector>

#include "semap/core/labels.hpp"
#include "objects/segment_graph.hpp"

namespace semap {

struct SupervoxelParams {
  float voxel_resolution = 0.01f;  ///< m
  float seed_resolution = 0.06f;   ///< m
  float colour_importance = 0.2f;
  float spatial_importance = 0.4f;
  float normal_importance = 1.0f;
  float adopt_radius = 0.03f;  ///< m, unowned points join the nearest owned point's supervoxel within this (0: drop them)
};

/// Supervoxels of `points` (camera frame, metres) with their adjacency. Node normals point
/// towards the camera (origin); point_indices index `points`. Points VCCS leaves unassigned
/// join the supervoxel of the nearest assigned point within adopt_radius, else no node.
SupervoxelGraph build_supervoxel_graph(const std::vector<Eigen::Vector3f>& points, const std::vector<Rgb8>& colours,
                                       const SupervoxelParams& params);

}  // namespace semap
