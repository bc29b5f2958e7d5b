// The one translation unit of the project that includes PCL (issue 6: PCL compiles slowly).
#include "objects/supervoxel_graph.hpp"

#include <pcl/point_cloud.h>
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
  for (size_t i = 0; i < labelled->size() && i < points.size(); ++i) {
    const auto it = node_of_label.find((*labelled)[i].label);
    if (it != node_of_label.end()) graph.nodes[it->second].point_indices.push_back(static_cast<int>(i));
  }
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
