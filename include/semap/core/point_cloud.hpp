#pragma once
// The one point-cloud type (structure of arrays; optional attributes are empty or sized like
// `points`) and the triangle mesh built on it.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "semap/core/labels.hpp"

namespace semap {

struct PointCloud {
  std::vector<Eigen::Vector3f> points;
  std::vector<Eigen::Vector3f> normals;   ///< optional
  std::vector<Rgb8> colours;              ///< optional
  std::vector<ClassId> labels;            ///< optional, project class ids
  std::vector<uint32_t> instances;        ///< optional, 0 = none

  size_t size() const { return points.size(); }
  bool empty() const { return points.empty(); }
  bool has_normals() const { return !normals.empty(); }
  bool has_colours() const { return !colours.empty(); }
  bool has_labels() const { return !labels.empty(); }
  bool has_instances() const { return !instances.empty(); }
  void reserve(size_t n);
  void clear();
  /// Appends point i of `other` (attributes the two clouds share).
  void push_back_from(const PointCloud& other, size_t i);
  /// True when every optional attribute is empty or matches points.size().
  bool consistent() const;
};

struct TriangleMesh {
  PointCloud vertices;
  std::vector<std::array<uint32_t, 3>> triangles;
};

}  // namespace semap
