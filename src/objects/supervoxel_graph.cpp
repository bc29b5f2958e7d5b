// The one translation unit of the project that includes PCL (issue 6: PCL compiles slowly).
#include "objects/supervoxel_graph.hpp"

#include <pcl/point_cloud.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_types.h>
#include <pcl/segmentation/supervoxel_clustering.h>

#include <map>
#include <unordered_map>

namespace semap {

SupervoxelGraph build_supervoxel_graph(const std::vector<Eigen::Vector3f>& points, const std::vector<Rgb8>& colours,
                                       const SupervoxelParams& params) {
  SupervoxelGraph graph;
  if (points.size() < 10) return graph;
  pcl::PointCloud<pcl::PointXYZRGBA>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZRGBA>);
  cloud->resize(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    auto& p = (*cloud)[i];
    p.x = points[i].x();
    p.y = points[i].y();
    p.z = points[i].z();
    if (i < colours.size()) {
      p.r = colours[i].r;
      p.g = colours[i].g;
      p.b = colours[i].b;
    }
    p.a = 255;
  }
  // METHODS.md C2.1: VCCS, seeds on a regular grid, clustering by colour, position, normals.
  pcl::SupervoxelClustering<pcl::PointXYZRGBA> vccs(params.voxel_resolution, params.seed_resolution);
  vccs.setUseSingleCameraTransform(false);
  vccs.setInputCloud(cloud);
  vccs.setColorImportance(params.colour_importance);
  vccs.setSpatialImportance(params.spatial_importance);
  vccs.setNormalImportance(params.normal_importance);
  std::map<std::uint32_t, pcl::Supervoxel<pcl::PointXYZRGBA>::Ptr> clusters;
  vccs.extract(clusters);
  if (clusters.empty()) return graph;

  std::unordered_map<std::uint32_t, int> node_of_label;
  for (const auto& [label, sv] : clusters) {
    SupervoxelNode node;
    node.centroid = Eigen::Vector3f(sv->centroid_.x, sv->centroid_.y, sv->centroid_.z);
    Eigen::Vector3f n(sv->normal_.normal_x, sv->normal_.normal_y, sv->normal_.normal_z);
    if (!n.allFinite() || n.norm() < 1e-6f) n = -node.centroid.normalized();
    n.normalize();
    if (n.dot(node.centroid) > 0.f) n = -n;  // face the camera at the origin
    node.normal = n;
    node.curvature = std::isfinite(sv->normal_.curvature) ? sv->normal_.curvature : 1.f;
    node_of_label[label] = static_cast<int>(graph.nodes.size());
    graph.nodes.push_back(std::move(node));
  }
  const auto labelled = vccs.getLabeledCloud();
  std::vector<int> node_of_point(points.size(), -1);
  for (size_t i = 0; i < labelled->size() && i < points.size(); ++i) {
    const auto it = node_of_label.find((*labelled)[i].label);
    if (it != node_of_label.end()) node_of_point[i] = it->second;
  }
  // VCCS leaves voxels no seed's flow reached unowned (isolated and border voxels, thin parts):
  // they join the supervoxel of the nearest owned point within adopt_radius, so object
  // borders are not eroded by the supervoxel step.
  if (params.adopt_radius > 0.f) {
    pcl::PointCloud<pcl::PointXYZ>::Ptr owned(new pcl::PointCloud<pcl::PointXYZ>);
    std::vector<int> owned_index;
    for (size_t i = 0; i < node_of_point.size(); ++i)
      if (node_of_point[i] >= 0) {
        owned->push_back(pcl::PointXYZ(points[i].x(), points[i].y(), points[i].z()));
        owned_index.push_back(static_cast<int>(i));
      }
    if (!owned->empty() && owned->size() < points.size()) {
      pcl::KdTreeFLANN<pcl::PointXYZ> tree;
      tree.setInputCloud(owned);
      std::vector<int> nearest(1);
      std::vector<float> dist_sq(1);
      const float limit_sq = params.adopt_radius * params.adopt_radius;
      for (size_t i = 0; i < node_of_point.size(); ++i) {
        if (node_of_point[i] >= 0 || !points[i].allFinite()) continue;
        const pcl::PointXYZ q(points[i].x(), points[i].y(), points[i].z());
        if (tree.nearestKSearch(q, 1, nearest, dist_sq) == 1 && dist_sq[0] <= limit_sq)
          node_of_point[i] = node_of_point[owned_index[nearest[0]]];
      }
    }
  }
  for (size_t i = 0; i < node_of_point.size(); ++i)
    if (node_of_point[i] >= 0) graph.nodes[node_of_point[i]].point_indices.push_back(static_cast<int>(i));
  std::multimap<std::uint32_t, std::uint32_t> adjacency;
  vccs.getSupervoxelAdjacency(adjacency);
  for (const auto& [a, b] : adjacency) {
    const auto ia = node_of_label.find(a), ib = node_of_label.find(b);
    if (ia == node_of_label.end() || ib == node_of_label.end() || ia->second >= ib->second) continue;
    graph.edges.emplace_back(ia->second, ib->second);
  }
  return graph;
}

}  // namespace semap
