#pragma once
// One object of the object map as a user reads it (METHODS.md C2-C5 output): what
// objects.json holds and what semap::Mapper::objects() returns.
#include <Eigen/Core>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "semap/core/labels.hpp"

namespace semap {

/// Oriented box of a point set by PCA: centre, full side lengths, world_from_box rotation.
struct OrientedBox {
  Eigen::Vector3f center = Eigen::Vector3f::Zero();
  Eigen::Vector3f extent = Eigen::Vector3f::Zero();
  Eigen::Matrix3f rotation = Eigen::Matrix3f::Identity();
};

/// One object of the map as a user reads it (world frame, metres): what objects.json holds.
struct ObjectSummary {
  uint32_t id = 0;
  ClassId class_id = 0;
  std::map<std::string, double> class_distribution;  ///< class name -> share of the class evidence (>= 0.005)
  double confidence = 0.0;  ///< mean detector score of the segments merged in (0..1)
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
  OrientedBox box;  ///< of the object's body (largest cluster, trimmed)
  Eigen::Vector3f aabb_min = Eigen::Vector3f::Zero(), aabb_max = Eigen::Vector3f::Zero();
  std::vector<Eigen::Vector3f> points;  ///< one per occupied object voxel
  std::vector<Rgb8> colours;
  int merge_count = 0;   ///< segments merged in (C4 n)
  int associations = 0;  ///< association count over the run (C5 s)
  size_t first_frame = 0, last_frame = 0;
  std::string state;     ///< new | stable
  /// JPEG crop (longest side <= 96 px) of the keyframe that saw the object best: its largest
  /// unoccluded view (objects/best_views.hpp), kept in map.semap through resume and merge; empty
  /// when none (e.g. from a map written before views were saved). Shown by report.html, not
  /// written to objects.json.
  std::string best_view_jpeg;
};
nlohmann::json to_json(const ObjectSummary& object);
/// The objects.json document ({"objects": [...]}, schema in SHARED_FORMATS.md).
nlohmann::json objects_json(const std::vector<ObjectSummary>& objects);

}  // namespace semap
